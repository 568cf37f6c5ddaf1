/* ShadyLoc — FAST grid detection and stereo measurements. */
#include <shadyloc/core/Options.h>
#include <shadyloc/core/Units.h>
#include <shadyloc/features/StereoFeatures.h>

#include <mrpt/config/CConfigFileBase.h>

#include <Eigen/Dense>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <type_traits>
#include <vector>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace shadyloc::features
{
namespace
{
using Clock = std::chrono::steady_clock;
using core::msSince;
}  // namespace

// ---- options ------------------------------------------------------------------
const char* toString(DescriptorKind k) { return k == DescriptorKind::Orb ? "orb" : "brief"; }

/** Keys renamed to carry their unit (the members keep their names). */
static const std::vector<core::TRenamedKey> kRenamedFeatureKeys = {
	{"min_disparity", "min_disparity_px"},
	{"max_disparity", "max_disparity_px"},
	{"row_tolerance", "row_tolerance_px"},
	{"patch_radius", "patch_radius_px"},
	{"brief_patch_size", "brief_patch_size_px"},
	{"max_depth", "max_depth_m"},
	{"presmooth_sigma", "presmooth_sigma_px"},
};

void TStereoFeatureOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	v.renamed(kRenamedFeatureKeys);
	v("fast_threshold", fast_threshold, "grey levels", Range::closed(1, 254), "FAST threshold");
	v("grid_cols", grid_cols, "", Range::atLeast(1), "buckets across");
	v("grid_rows", grid_rows, "", Range::atLeast(1), "buckets down");
	// 0 or less used to mean "no limit" without saying so.
	v("max_per_cell", max_per_cell, "", Range::atLeast(1), "left corners kept per bucket");
	v("max_per_cell_right", max_per_cell_right, "", Range::atLeast(1), "right corners kept per bucket");
	v("min_disparity_px", min_disparity, "px", Range::above(0), "true disparity fx*b/Z");
	v("max_disparity_px", max_disparity, "px", Range::any(), "true disparity fx*b/Z");
	v("row_tolerance_px", row_tolerance, "px", Range::closed(0, 3), "candidate rows +-");
	v("patch_radius_px", patch_radius, "px", Range::closed(1, 7), "ZNCC patch (2r+1)^2");
	v("min_zncc", min_zncc, "", Range::open(-1, 1), "weakest stereo correlation");
	v("max_ambiguity", max_ambiguity, "", Range::openClosed(0, 1), "(1-best)/(1-second) bound");
	v("lr_tolerance_px", lr_tolerance_px, "px", Range::any(), "left-right check");
	v("min_zncc_shifted", min_zncc_shifted, "", Range::any(), "silhouette check, -1 = off");
	// The describer's own check would name neither the key nor the file.
	v("brief_patch_size_px", brief_patch_size, "px", Range::closed(8, 250), "BRIEF patch side");
	v("brief_seed", brief_seed, "", Range::any(), "BRIEF pattern seed");
	v("sigma_px", sigma_px, "px", Range::above(0), "pixel noise for landmark covariance");
	v("max_depth_m", max_depth, "m", Range::above(0), "farthest landmark kept");
	v("presmooth_sigma_px", presmooth_sigma, "px", Range::closed(0, 5), "Gaussian pre-smoothing, 0 = off");
	v("subpixel_iterations", subpixel_iterations, "", Range::closed(0, 20), "Gauss-Newton steps on uR, 0 = parabola only");
	v("dense_check", dense_check, "", Range::any(), "verify the match against every shift of the range");
	v("shifted_window_check", shifted_window_check, "", Range::any(),
	  "four corner-holding windows must agree (needs dense_check)");
	v("shifted_window_margin", shifted_window_margin, "", Range::closed(0, 2),
	  "ZNCC a shifted window's other peak may exceed the match by");
	v.choice("descriptor", descriptor, {{"brief", DescriptorKind::Brief}, {"orb", DescriptorKind::Orb}},
			 "brief (single-scale FAST + BRIEF) or orb (OpenCV ORB: pyramid, orientation)");
	v("orb_levels", orb_levels, "", Range::closed(1, 16), "ORB pyramid levels, 1 = single scale");
	v("orb_scale_factor", orb_scale_factor, "", Range::openClosed(1, 2), "ORB size ratio of neighbouring levels");
	v("orb_right_levels", orb_right_levels, "", Range::closed(0, 16),
	  "ORB levels the right image's stereo candidates come from, 0 = all");
}

void TStereoFeatureOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::loadKeys(*this, c, s);
}

void TStereoFeatureOptions::dumpToTextStream(std::ostream& o) const { core::dumpKeys(*this, o); }

void TStereoFeatureOptions::validate() const
{
	core::checkKeys(*this);
	if (brief_patch_size % 2) throw std::invalid_argument("brief_patch_size_px: must be even");
	if (!(max_disparity > min_disparity)) throw std::invalid_argument("max_disparity_px: must exceed min_disparity_px");
}

// ---- FAST on a grid -----------------------------------------------------------
void spreadOverGrid(
	const std::vector<cv::KeyPoint>& all, int W, int H, int cols, int rows, int perCell, int border,
	std::vector<cv::KeyPoint>& out)
{
	out.clear();
	std::vector<std::vector<cv::KeyPoint>> cells(static_cast<size_t>(cols * rows));
	for (const auto& k : all)
	{
		const int x = static_cast<int>(k.pt.x), y = static_cast<int>(k.pt.y);
		if (x < border || y < border || x >= W - border || y >= H - border) continue;
		const int cx = std::min(cols - 1, x * cols / W), cy = std::min(rows - 1, y * rows / H);
		cells[cy * cols + cx].push_back(k);
	}
	for (auto& c : cells)
	{
		if (perCell > 0 && static_cast<int>(c.size()) > perCell)
		{
			std::nth_element(c.begin(), c.begin() + perCell, c.end(), [](const auto& a, const auto& b) {
				return a.response > b.response;
			});
			c.resize(perCell);
		}
		out.insert(out.end(), c.begin(), c.end());
	}
}

void detectFastGrid(
	const cv::Mat& grey8, int threshold, int cols, int rows, int perCell, int border,
	std::vector<cv::KeyPoint>& out)
{
	std::vector<cv::KeyPoint> all;
	cv::FAST(grey8, all, threshold, true, cv::FastFeatureDetector::TYPE_9_16);
	spreadOverGrid(all, grey8.cols, grey8.rows, cols, rows, perCell, border, out);
}

// ---- detection and description ---------------------------------------------------
namespace
{
/** OpenCV's ORB as the options set it. FAST_SCORE: corners are ranked (by
 * ORB within a level, by the grid, by the map's strongest-corner selection)
 * by the same FAST score as single-scale FAST, which the map stores as a
 * 16-bit integer; ORB's Harris scores are tiny fractions. `edge` is ORB's
 * edge threshold: corners closer to a level's edge are not detected. */
cv::Ptr<cv::ORB> makeOrb(const TStereoFeatureOptions& o, int nFeatures, int edge)
{
	return cv::ORB::create(
		nFeatures, static_cast<float>(o.orb_scale_factor), o.orb_levels, edge, 0, 2, cv::ORB::FAST_SCORE,
		kOrbPatchSize, o.fast_threshold);
}

/** Half-width of each row of ORB's circular orientation patch of radius h
 * (rows 0..h): the rounded circle, made symmetric under swapping rows and
 * columns, as ORB measures it (so that its descriptors see the same angle). */
std::vector<int> orientationRowEnds(int h)
{
	std::vector<int> end(static_cast<size_t>(h) + 2, 0);
	const int vmax = cvFloor(h * std::sqrt(2.f) / 2 + 1), vmin = cvCeil(h * std::sqrt(2.f) / 2);
	for (int v = 0; v <= vmax; v++) end[v] = cvRound(std::sqrt(double(h) * h - v * v));
	// The rows above the diagonal take the columns' extents below it.
	for (int v = h, col = 0; v >= vmin; v--, col++)
	{
		while (end[col] == end[col + 1]) col++;
		end[v] = col;
	}
	return end;
}

/** Orientation [deg] of the circular patch (radius h) at integer (x, y):
 * the direction of its intensity centroid (Rublee et al., "ORB: an
 * efficient alternative to SIFT or SURF", ICCV 2011, eq. 1-3). */
float centroidAngleDeg(const cv::Mat& img, int x, int y, int h, const std::vector<int>& rowEnd)
{
	const uint8_t* c = img.ptr<uint8_t>(y) + x;
	const ptrdiff_t step = static_cast<ptrdiff_t>(img.step);
	int m01 = 0, m10 = 0;
	for (int u = -h; u <= h; u++) m10 += u * c[u];
	for (int v = 1; v <= h; v++)
	{
		int rowDiff = 0;
		for (int u = -rowEnd[v]; u <= rowEnd[v]; u++)
		{
			const int below = c[u + v * step], above = c[u - v * step];
			rowDiff += below - above;
			m10 += u * (below + above);
		}
		m01 += v * rowDiff;
	}
	return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

/** One level of ORB's pyramid: the image and its scale to level 0. */
struct TPyramidLevel
{
	cv::Mat img;
	float scale = 1.f;
};

/** ORB's detection without its orientations: its pyramid of n levels (each
 * level resized from the one before), FAST with non-maximum suppression per level,
 * corners within `edge` px of a level's edge dropped, the strongest kept per
 * level in ORB's shares of `nFeatures`; positions in level-0 pixels, octave
 * and size set. The same corners in the same order as cv::ORB::detect
 * (FeaturesOrb.CornersAreOpenCvOrbsWithAnglesWhereDescribed), without the
 * orientation of every corner: most are never described. */
std::vector<TPyramidLevel> orbPyramidCorners(
	const cv::Mat& grey8, const TStereoFeatureOptions& o, int n, int nFeatures, int edge, std::vector<cv::KeyPoint>& all)
{
	const double scaleFactor = static_cast<float>(o.orb_scale_factor);	// ORB keeps it as the float it was given
	std::vector<TPyramidLevel> levels(static_cast<size_t>(n));
	// ORB's share per level: a geometric series over the levels' areas.
	const float factor = static_cast<float>(1.0 / scaleFactor);
	float share = nFeatures * (1 - factor) / (1 - static_cast<float>(std::pow(double(factor), double(n))));
	std::vector<int> perLevel(static_cast<size_t>(n));
	int sum = 0;
	for (int l = 0; l + 1 < n; l++, share *= factor) sum += perLevel[l] = cvRound(share);
	perLevel[n - 1] = std::max(nFeatures - sum, 0);
	all.clear();
	std::vector<cv::KeyPoint> kps;
	for (int l = 0; l < n; l++)
	{
		auto& L = levels[l];
		L.scale = static_cast<float>(std::pow(scaleFactor, double(l)));
		if (l == 0)
			L.img = grey8;
		else
		{
			const float inv = 1.0f / L.scale;
			const cv::Size sz(cvRound(grey8.cols * inv), cvRound(grey8.rows * inv));
			cv::resize(levels[l - 1].img, L.img, sz, 0, 0, cv::INTER_LINEAR_EXACT);
		}
		cv::FAST(L.img, kps, o.fast_threshold, true, cv::FastFeatureDetector::TYPE_9_16);
		cv::KeyPointsFilter::runByImageBorder(kps, L.img.size(), edge);
		cv::KeyPointsFilter::retainBest(kps, perLevel[l]);
		for (auto& k : kps)
		{
			k.octave = l;
			k.size = kOrbPatchSize * L.scale;
			k.pt *= L.scale;
		}
		all.insert(all.end(), kps.begin(), kps.end());
	}
	return levels;
}

/** Sets the ORB orientation of corners found by orbPyramidCorners, on the
 * level each was found in. A patch reaching over a level's edge reads the
 * edge reflected, as ORB's bordered pyramid does. */
void setOrbAngles(const std::vector<TPyramidLevel>& levels, std::vector<cv::KeyPoint>& kps)
{
	constexpr int h = kOrbPatchSize / 2;
	static const std::vector<int> rowEnd = orientationRowEnds(h);
	std::vector<cv::Mat> padded(levels.size());	 // made only where a patch needs it
	for (auto& k : kps)
	{
		const auto& L = levels[static_cast<size_t>(k.octave)];
		const int x = cvRound(k.pt.x / L.scale), y = cvRound(k.pt.y / L.scale);
		if (x >= h && y >= h && x + h < L.img.cols && y + h < L.img.rows)
		{
			k.angle = centroidAngleDeg(L.img, x, y, h, rowEnd);
			continue;
		}
		cv::Mat& P = padded[static_cast<size_t>(k.octave)];
		if (P.empty()) cv::copyMakeBorder(L.img, P, h, h, h, h, cv::BORDER_REFLECT_101 + cv::BORDER_ISOLATED);
		k.angle = centroidAngleDeg(P, x + h, y + h, h, rowEnd);
	}
}
}  // namespace

CornerDescriber::CornerDescriber(const TStereoFeatureOptions& o) : m_opts(o), m_brief(o.brief_patch_size, o.brief_seed)
{
	// ORB's descriptor patch lies inside the image (ORB's own edge threshold);
	// BRIEF's inside its S x S square.
	const int descRadius = o.descriptor == DescriptorKind::Orb ? kOrbPatchSize : m_brief.radius() + 1;
	m_border = std::max({descRadius, o.patch_radius + 4, kPatchSize / 2 + 3});
}

void CornerDescriber::detect(
	const cv::Mat& grey8, int perCell, int border, std::vector<cv::KeyPoint>& out, CornerUse use) const
{
	const auto& o = m_opts;
	if (o.descriptor == DescriptorKind::Brief)
	{
		detectFastGrid(grey8, o.fast_threshold, o.grid_cols, o.grid_rows, perCell, border, out);
		return;
	}
	// ORB keeps its nFeatures best per level by score, not spread: ask for
	// several times what the grid keeps and let the grid choose (all when
	// perCell <= 0). Its edge threshold is the border, so no corner the grid
	// would keep is lost before it (the right image's candidates reach closer
	// to the edge than described corners). Orientations only for the corners
	// kept, and only where they will be described.
	const int cells = o.grid_cols * o.grid_rows;
	const int nFeatures = perCell > 0 ? 4 * cells * perCell : 1 << 20;
	std::vector<cv::KeyPoint> all;
	const int nLevels = use == CornerUse::Candidates && o.orb_right_levels > 0 ? std::min(o.orb_levels, o.orb_right_levels)
																			   : o.orb_levels;
	const auto levels = orbPyramidCorners(grey8, o, nLevels, nFeatures, std::max(border, 3), all);
	spreadOverGrid(all, grey8.cols, grey8.rows, o.grid_cols, o.grid_rows, perCell, border, out);
	if (use == CornerUse::Described) setOrbAngles(levels, out);
}

void CornerDescriber::describe(
	const cv::Mat& grey8, const std::vector<cv::KeyPoint>& kps, std::vector<TBriefDescriptor>& desc,
	std::vector<uint8_t>& ok, cv::Mat* smoothedOut) const
{
	desc.assign(kps.size(), TBriefDescriptor());
	ok.assign(kps.size(), 0);
	if (smoothedOut) smoothedOut->release();
	if (m_opts.descriptor == DescriptorKind::Brief)
	{
		cv::Mat smoothed;
		BriefExtractor::smooth(grey8, smoothed);
		if (smoothedOut) *smoothedOut = smoothed;
		for (size_t i = 0; i < kps.size(); i++)
			ok[i] = m_brief.compute(
				smoothed, static_cast<int>(std::floor(kps[i].pt.x)), static_cast<int>(std::floor(kps[i].pt.y)), desc[i]);
		return;
	}
	// ORB's compute drops corners near the edges and regroups the rest by
	// level: class_id carries each corner's index through it. The angle and
	// octave are the detector's (compute keeps given keypoints' angles).
	std::vector<cv::KeyPoint> tagged(kps);
	for (size_t i = 0; i < tagged.size(); i++) tagged[i].class_id = static_cast<int>(i);
	cv::Mat d;
	makeOrb(m_opts, static_cast<int>(std::max<size_t>(1, kps.size())), kOrbPatchSize)->compute(grey8, tagged, d);
	for (size_t j = 0; j < tagged.size(); j++)
	{
		const int i = tagged[j].class_id;
		if (i < 0 || static_cast<size_t>(i) >= kps.size()) continue;
		std::memcpy(desc[i].w.data(), d.ptr<uint8_t>(static_cast<int>(j)), 32);
		ok[i] = 1;
	}
}

namespace
{
/** The sums of zncc over a (2r+1)^2 window. With R > 0 the radius is R,
 * fixed at compile time (the stereo matcher's hot loop: unrolled and
 * vectorised by the compiler), with 32-bit sums: (2R+1)^2 * 255^2 < 2^31
 * for R <= 90. R = 0 takes r at run time, with 64-bit squares. Integer sums
 * are exact in any order, so both give the same values. */
template <int R>
void znccSums(const cv::Mat& a, int xa, int ya, const cv::Mat& b, int xb, int yb, int r, int64_t s[5])
{
	static_assert(R >= 0 && R <= 90);
	using Square = std::conditional_t<(R > 0), int32_t, int64_t>;
	const int rr = R > 0 ? R : r;
	int32_t sa = 0, sb = 0;
	Square saa = 0, sbb = 0, sab = 0;
	for (int dy = -rr; dy <= rr; dy++)
	{
		const uint8_t* pa = a.ptr<uint8_t>(ya + dy) + xa - rr;
		const uint8_t* pb = b.ptr<uint8_t>(yb + dy) + xb - rr;
		for (int dx = 0; dx <= 2 * rr; dx++)
		{
			const int32_t va = pa[dx], vb = pb[dx];
			sa += va;
			sb += vb;
			saa += va * va;
			sbb += vb * vb;
			sab += va * vb;
		}
	}
	s[0] = sa, s[1] = sb, s[2] = saa, s[3] = sbb, s[4] = sab;
}
}  // namespace

float zncc(const cv::Mat& a, int xa, int ya, const cv::Mat& b, int xb, int yb, int r)
{
	int64_t s[5];
	switch (r)
	{
		case 2: znccSums<2>(a, xa, ya, b, xb, yb, r, s); break;
		case 3: znccSums<3>(a, xa, ya, b, xb, yb, r, s); break;
		case 4: znccSums<4>(a, xa, ya, b, xb, yb, r, s); break;
		default: znccSums<0>(a, xa, ya, b, xb, yb, r, s);
	}
	const int64_t sa = s[0], sb = s[1], saa = s[2], sbb = s[3], sab = s[4];
	const double n = (2 * r + 1) * (2 * r + 1);
	const double va = saa - double(sa) * sa / n, vb = sbb - double(sb) * sb / n;
	if (va < 1e-6 || vb < 1e-6) return -1.f;
	return static_cast<float>((sab - double(sa) * sb / n) / std::sqrt(va * vb));
}

bool matchAlongRow(
	const cv::Mat& left, int xl, int y, const cv::Mat& right, float uRPred, int halfRange, int r, float minZncc,
	int iterations, float& uR)
{
	const int x0 = static_cast<int>(std::lround(uRPred));
	const int lo = x0 - halfRange - 1, hi = x0 + halfRange + 1;	// one beyond, for the parabola
	if (xl - r < 0 || xl + r >= left.cols || y - r < 0 || y + r >= left.rows || lo - r < 0 || hi + r >= right.cols)
		return false;
	std::vector<float> c(static_cast<size_t>(hi - lo + 1));
	for (int x = lo; x <= hi; x++) c[static_cast<size_t>(x - lo)] = zncc(left, xl, y, right, x, y, r);
	const auto best = std::max_element(c.begin() + 1, c.end() - 1);
	if (*best < minZncc) return false;
	const size_t i = static_cast<size_t>(best - c.begin());
	const float xs = static_cast<float>(lo + static_cast<int>(i)) + parabolaPeak(c[i - 1], c[i], c[i + 1]);
	uR = iterations > 0 ? refineRowShift(left, xl, y, right, xs, r, iterations) : xs;
	return true;
}

namespace
{
/** Keys' cubic convolution weights (a = -1/2) at fraction t and their derivatives. */
void keysWeights(double t, double w[4], double dw[4])
{
	w[0] = 0.5 * (-t + 2 * t * t - t * t * t);
	w[1] = 0.5 * (2 - 5 * t * t + 3 * t * t * t);
	w[2] = 0.5 * (t + 4 * t * t - 3 * t * t * t);
	w[3] = 0.5 * (-t * t + t * t * t);
	dw[0] = 0.5 * (-1 + 4 * t - 3 * t * t);
	dw[1] = 0.5 * (-10 * t + 9 * t * t);
	dw[2] = 0.5 * (1 + 8 * t - 9 * t * t);
	dw[3] = 0.5 * (-2 * t + 3 * t * t);
}
}  // namespace

float refineRowShift(
	const cv::Mat& left, int xl, int y, const cv::Mat& right, float x0, int r, int iterations)
{
	// The cubic needs samples x-1..x+2 around every patch column. Only the
	// right eye is interpolated: sampling both at mirror-image fractions
	// (+-s/2) was tried and doubled the residual bias (0.045 instead of 0.018 px
	// on FeaturesSubpixel's texture): the cubic's phase errors then add up.
	const double lo = r + 1, hi = right.cols - r - 3;
	if (iterations <= 0 || !(x0 - 1 >= lo && x0 + 1 < hi) || xl - r < 0 || xl + r >= left.cols ||
		y - r < 0 || y + r >= left.rows)
		return x0;
	double x = x0, g = 1, c = 0;
	double w[4], dw[4];
	for (int it = 0; it < iterations; it++)
	{
		const int i0 = static_cast<int>(std::floor(x));
		keysWeights(x - i0, w, dw);
		// Normal equations of (dx, dg, dc); residual e = R(x + dx) - g L - c,
		// Jacobian (R'(x + dx), -L, -1).
		Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
		Eigen::Vector3d b = Eigen::Vector3d::Zero();
		for (int dy = -r; dy <= r; dy++)
		{
			const uint8_t* pl = left.ptr<uint8_t>(y + dy) + xl;
			const uint8_t* pr = right.ptr<uint8_t>(y + dy) + i0 - 1;
			for (int dx = -r; dx <= r; dx++)
			{
				const uint8_t* q = pr + dx;
				const double R = w[0] * q[0] + w[1] * q[1] + w[2] * q[2] + w[3] * q[3];
				const double Rd = dw[0] * q[0] + dw[1] * q[1] + dw[2] * q[2] + dw[3] * q[3];
				const double L = pl[dx];
				const double e = R - g * L - c;
				const Eigen::Vector3d J(Rd, -L, -1);
				H.noalias() += J * J.transpose();
				b.noalias() += J * e;
			}
		}
		const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
		if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) return x0;
		const Eigen::Vector3d d = -ldlt.solve(b);
		x += d[0];
		g += d[1];
		c += d[2];
		if (!std::isfinite(x) || std::abs(x - x0) > 1 || x < lo || x >= hi) return x0;
		if (std::abs(d[0]) < 1e-3) break;
	}
	return static_cast<float>(x);
}

bool refinePatch2D(
	const uint8_t* tmpl, int size, const cv::Mat& img, float x0, float y0, int iterations, float& xOut,
	float& yOut)
{
	const int h = size / 2;
	// The cubic needs samples -1..+2 around every template pixel.
	const auto inside = [&](double x, double y) {
		return x - h - 1 >= 1 && y - h - 1 >= 1 && x + h + 3 < img.cols && y + h + 3 < img.rows;
	};
	if (iterations <= 0 || !inside(x0, y0)) return false;
	double x = x0, y = y0, g = 1, c = 0;
	for (int it = 0; it < iterations; it++)
	{
		const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
		double wx[4], dwx[4], wy[4], dwy[4];
		keysWeights(x - ix, wx, dwx);
		keysWeights(y - iy, wy, dwy);
		// The cubic is separable: each image row's horizontal sums once
		// (size + 3 rows), then the vertical sums per template pixel, in the
		// same order as the direct 4x4 sum, so the result is the same.
		const int rows = size + 3;
		thread_local std::vector<double> S, SD;
		S.resize(size_t(rows) * size);
		SD.resize(size_t(rows) * size);
		for (int k = 0; k < rows; k++)
		{
			const uint8_t* row = img.ptr<uint8_t>(iy - h - 1 + k) + ix - h - 1;
			for (int dx = 0; dx < size; dx++)
			{
				const uint8_t* q = row + dx;
				S[k * size + dx] = wx[0] * q[0] + wx[1] * q[1] + wx[2] * q[2] + wx[3] * q[3];
				SD[k * size + dx] = dwx[0] * q[0] + dwx[1] * q[1] + dwx[2] * q[2] + dwx[3] * q[3];
			}
		}
		double H[4][4] = {}, b[4] = {};
		for (int ty = 0; ty < size; ty++)
			for (int tx = 0; tx < size; tx++)
			{
				double I = 0, Ix = 0, Iy = 0;
				for (int k = 0; k < 4; k++)
				{
					const double s = S[(ty + k) * size + tx], sd = SD[(ty + k) * size + tx];
					I += wy[k] * s;
					Iy += dwy[k] * s;
					Ix += wy[k] * sd;
				}
				const double T = tmpl[ty * size + tx];
				const double e = I - g * T - c;
				const double J[4] = {Ix, Iy, -T, -1};
				for (int i = 0; i < 4; i++)
				{
					for (int j = 0; j <= i; j++) H[i][j] += J[i] * J[j];
					b[i] += J[i] * e;
				}
			}
		const Eigen::Matrix4d Hm = Eigen::Matrix4d::Map(&H[0][0]).selfadjointView<Eigen::Upper>();
		const Eigen::Vector4d bv(b[0], b[1], b[2], b[3]);
		const Eigen::LDLT<Eigen::Matrix4d> ldlt(Hm);
		if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) return false;
		const Eigen::Vector4d d = -ldlt.solve(bv);
		x += d[0];
		y += d[1];
		g += d[2];
		c += d[3];
		if (!std::isfinite(x) || !std::isfinite(y) || std::abs(x - x0) > 1 || std::abs(y - y0) > 1 ||
			!inside(x, y))
			return false;
		if (std::abs(d[0]) < 1e-3 && std::abs(d[1]) < 1e-3) break;
	}
	xOut = static_cast<float>(x);
	yOut = static_cast<float>(y);
	return true;
}

namespace
{
/** Standard deviation of the (2r+1)^2 patch at (x, y) [grey levels]. */
double patchStd(const cv::Mat& a, int x, int y, int r)
{
	int s = 0;
	int64_t ss = 0;
	for (int dy = -r; dy <= r; dy++)
	{
		const uint8_t* p = a.ptr<uint8_t>(y + dy) + x - r;
		for (int dx = 0; dx <= 2 * r; dx++)
		{
			s += p[dx];
			ss += p[dx] * p[dx];
		}
	}
	const double n = (2 * r + 1) * (2 * r + 1), m = s / n;
	return std::sqrt(std::max(0.0, ss / n - m * m));
}
}  // namespace

namespace
{
/** Window sums of the right image for denseRowZncc, computed per row on
 * first use (most rows are never needed) into buffers reused across frames. */
struct TRightWindowStats
{
	const cv::Mat* img = nullptr;
	int r = 0;
	std::vector<uint8_t> done;	//!< per row: computed this frame
	std::vector<int32_t> sum;  //!< per pixel: sum of the (2r+1)^2 window [grey levels]
	std::vector<float> invNorm;	 //!< per pixel: 1 / sqrt(sum (R - mean R)^2), 0 where flat
	std::vector<int32_t> colS, colQ;

	void reset(const cv::Mat& image8, int radius)
	{
		img = &image8;
		r = radius;
		done.assign(image8.rows, 0);
		const size_t N = size_t(image8.rows) * image8.cols;
		if (sum.size() < N) sum.resize(N), invNorm.resize(N);
		colS.resize(image8.cols);
		colQ.resize(image8.cols);
	}
	/** Row y's sums (r <= y < H - r); valid for x in [r, W - r - 1]. */
	void row(int y, const int32_t*& S, const float*& iN)
	{
		const int W = img->cols, w = 2 * r + 1, n = w * w;
		S = sum.data() + size_t(y) * W;
		iN = invNorm.data() + size_t(y) * W;
		if (done[y]) return;
		done[y] = 1;
		std::fill(colS.begin(), colS.end(), 0);
		std::fill(colQ.begin(), colQ.end(), 0);
		for (int dy = -r; dy <= r; dy++)
		{
			const uint8_t* p = img->ptr<uint8_t>(y + dy);
			for (int x = 0; x < W; x++) colS[x] += p[x], colQ[x] += p[x] * p[x];
		}
		int32_t* Sw = sum.data() + size_t(y) * W;
		float* Iw = invNorm.data() + size_t(y) * W;
		int64_t s = 0, q = 0;
		for (int x = 0; x < w - 1; x++) s += colS[x], q += colQ[x];
		for (int x = r; x < W - r; x++)
		{
			s += colS[x + r];
			q += colQ[x + r];
			Sw[x] = static_cast<int32_t>(s);
			Iw[x] = static_cast<float>(n * q - s * s);	// n^2 var: exact, < 2^31 for r <= 7
			s -= colS[x - r];
			q -= colQ[x - r];
		}
		// 1 / sqrt(var sum) = sqrt(n / (n^2 var)), 0 where flat.
		const float nf = static_cast<float>(n);
		int x = r;
#ifdef __SSE2__
		const __m128i z = _mm_setzero_si128();
		for (; x + 4 <= W - r; x += 4)
		{
			const __m128 v = _mm_loadu_ps(Iw + x);
			const __m128 pos = _mm_cmpgt_ps(v, _mm_castsi128_ps(z));
			const __m128 inv = _mm_sqrt_ps(_mm_div_ps(_mm_set1_ps(nf), _mm_max_ps(v, _mm_set1_ps(1.f))));
			_mm_storeu_ps(Iw + x, _mm_and_ps(pos, inv));
		}
#endif
		for (; x < W - r; x++) Iw[x] = Iw[x] > 0 ? std::sqrt(nf / Iw[x]) : 0.f;
	}
};

/** Dense ZNCC of the left patch centred at (xl, y) against every right
 * window on row y centred in [xmin, xmax] (all inside the image; xmax <=
 * W - r - 2, so the SSE2 loads stay inside the row). The right windows' sums
 * come from `R` (per row, cached), so each shift costs one (2r+1)^2 dot
 * product; SSE2 does 8 shifts at a time, two columns' products per 32-bit
 * lane (pmaddwd). Flat windows score -1. Same values as zncc() up to float
 * rounding. */
void denseRowZncc(
	const cv::Mat& left, int xl, int y, const cv::Mat& right, TRightWindowStats& R, int xmin,
	int xmax, int r, std::vector<float>& out, std::vector<int32_t>& acc)
{
	const int n = (2 * r + 1) * (2 * r + 1), w = 2 * r + 1, m = std::max(0, xmax - xmin + 1);
	out.assign(m, -1.f);
	if (m == 0) return;
	int sl = 0, sll = 0;
	for (int dy = -r; dy <= r; dy++)
	{
		const uint8_t* pl = left.ptr<uint8_t>(y + dy) + xl - r;
		for (int dx = 0; dx < w; dx++) sl += pl[dx], sll += pl[dx] * pl[dx];
	}
	const double ll = sll - double(sl) * sl / n;  // n var(L)
	if (ll < 1e-6) return;
	// A = sum (L - m) R, m the rounded mean of L (|L - m| <= 255 fits int16);
	// the exact numerator follows below.
	const int m16 = (sl + n / 2) / n;
	acc.assign(m, 0);
	int32_t* A = acc.data();
	int k0 = 0;
#ifdef __SSE2__
	{
		// Weights of column pairs (dx, dx + 1) per row, a zero past the window;
		// each block of 8 shifts accumulates in registers over the whole window.
		const int pairs = (w + 1) / 2;
		__m128i wts[8 * 15];  // (2r+1) rows x pairs, r <= 7
		for (int dy = 0; dy < w; dy++)
		{
			const uint8_t* pl = left.ptr<uint8_t>(y - r + dy) + xl - r;
			for (int p = 0; p < pairs; p++)
			{
				const int dx = 2 * p;
				const uint16_t la = static_cast<uint16_t>(pl[dx] - m16);
				const uint16_t lb = dx + 1 < w ? static_cast<uint16_t>(pl[dx + 1] - m16) : 0;
				wts[dy * pairs + p] = _mm_set1_epi32(static_cast<int32_t>(la | (uint32_t(lb) << 16)));
			}
		}
		const __m128i zero = _mm_setzero_si128();
		for (; k0 + 8 <= m; k0 += 8)
		{
			__m128i lo = zero, hi = zero;
			for (int dy = 0; dy < w; dy++)
			{
				const uint8_t* q = right.ptr<uint8_t>(y - r + dy) + xmin - r + k0;
				for (int p = 0; p < pairs; p++)
				{
					// pixels k..k+7 at columns dx and dx + 1, as int16; pmaddwd
					// multiplies int16 x int16 into int32, so no product overflows
					const __m128i v0 = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(q + 2 * p)), zero);
					const __m128i v1 = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(q + 2 * p + 1)), zero);
					const __m128i wt = wts[dy * pairs + p];
					lo = _mm_add_epi32(lo, _mm_madd_epi16(_mm_unpacklo_epi16(v0, v1), wt));
					hi = _mm_add_epi32(hi, _mm_madd_epi16(_mm_unpackhi_epi16(v0, v1), wt));
				}
			}
			_mm_storeu_si128(reinterpret_cast<__m128i*>(A + k0), lo);
			_mm_storeu_si128(reinterpret_cast<__m128i*>(A + k0 + 4), hi);
		}
	}
#endif
	for (int dy = -r; dy <= r; dy++)  // the remaining shifts (all without SSE2)
	{
		const uint8_t* pl = left.ptr<uint8_t>(y + dy) + xl - r;
		const uint8_t* q = right.ptr<uint8_t>(y + dy) + xmin - r;
		for (int dx = 0; dx < w; dx++)
		{
			const int lz = pl[dx] - m16;
			for (int k = k0; k < m; k++) A[k] += lz * q[dx + k];
		}
	}
	const int32_t* S;
	const float* iN;
	R.row(y, S, iN);
	S += xmin;
	iN += xmin;
	// sum (L - mean L) R = A - (mean L - m) sum R
	const float e = static_cast<float>(double(sl) / n - m16), iL = static_cast<float>(1.0 / std::sqrt(ll));
	float* o = out.data();
	for (int k = 0; k < m; k++)
		o[k] = iN[k] > 0 ? (static_cast<float>(A[k]) - e * static_cast<float>(S[k])) * iN[k] * iL : -1.f;
}

/** Index of the largest element (-1 when empty). */
int argMax(const std::vector<float>& v)
{
	return v.empty() ? -1 : static_cast<int>(std::max_element(v.begin(), v.end()) - v.begin());
}
}  // namespace

// ---- stereo -------------------------------------------------------------------
// The options are validated before the describer is built from them.
StereoFeatureExtractor::StereoFeatureExtractor(const TOptions& o) : m_opts(o), m_corners((o.validate(), o)) {}

namespace
{
/** Corner x positions per image row. */
struct RowIndex
{
	std::vector<std::vector<int>> rows;
	void build(const std::vector<cv::KeyPoint>& kps, int H)
	{
		rows.assign(H, {});
		for (const auto& k : kps) rows[static_cast<int>(k.pt.y)].push_back(static_cast<int>(k.pt.x));
	}
};

struct TBest
{
	int x = -1;
	float s1 = -2.f, s2 = -2.f;	 //!< best and second-best (distinct position) scores
};

/** Best candidate of `rows` (rows y-tol..y+tol, x in [xmin, xmax]) for the
 * patch of `from` at (x0, y) compared with `to` on row y. */
TBest bestOnRow(
	const cv::Mat& from, int x0, int y, const cv::Mat& to, const RowIndex& idx, int tol, int xmin,
	int xmax, int r)
{
	TBest b;
	const int H = to.rows, W = to.cols;
	xmin = std::max(xmin, r + 2);
	xmax = std::min(xmax, W - r - 3);
	std::vector<std::pair<int, float>> cand;
	for (int yy = std::max(0, y - tol); yy <= std::min(H - 1, y + tol); yy++)
		for (int x : idx.rows[yy])
			if (x >= xmin && x <= xmax) cand.emplace_back(x, zncc(from, x0, y, to, x, y, r));
	for (const auto& c : cand)
		if (c.second > b.s1)
		{
			b.s1 = c.second;
			b.x = c.first;
		}
	// The second best must be elsewhere: corners one pixel apart (neighbouring
	// rows) are the same image structure, not a competing match.
	for (const auto& c : cand)
		if (std::abs(c.first - b.x) > 1 && c.second > b.s2) b.s2 = c.second;
	return b;
}
}  // namespace

namespace
{
struct TPair
{
	int kp;
	float uR, s;
};

/** Climbs the left patch's correlation along the right row from x to the
 * local maximum (at most two steps); false when none is reached. c0, cm, cp:
 * the scores at the peak and beside it. */
bool climbToPeak(
	const cv::Mat& left, int xl, int y, const cv::Mat& right, int r, int& x, float& c0, float& cm, float& cp)
{
	const int W = left.cols;
	c0 = zncc(left, xl, y, right, x, y, r);
	for (int step = 0; step < 3; step++)
	{
		if (x - 1 < r + 1 || x + 1 > W - r - 2) return false;
		cm = zncc(left, xl, y, right, x - 1, y, r);
		cp = zncc(left, xl, y, right, x + 1, y, r);
		if (c0 >= cm && c0 >= cp) return true;
		if (cm > cp)
		{
			x--;
			cp = c0;
			c0 = cm;
		}
		else
		{
			x++;
			cm = c0;
			c0 = cp;
		}
	}
	return false;
}

/** One left corner's stereo match through every check the options turn on. */
struct TCornerMatcher
{
	const StereoFeatureExtractor::TOptions& o;
	const geometry::TStereoCalib& calib;
	const cv::Mat &left, &right;
	const RowIndex &rowsR, &rowsL;
	TRightWindowStats& rightStats;	//!< of `right`, when dense_check
	std::vector<float> dense;  //!< scratch
	std::vector<int32_t> denseAcc;	//!< scratch

	struct TMatch
	{
		float uR, s;
	};

	std::optional<TMatch> match(const cv::KeyPoint& k)
	{
		const int r = o.patch_radius, xl = static_cast<int>(k.pt.x), y = static_cast<int>(k.pt.y);
		const double doffs = calib.doffs();
		// uR = uL + doffs - D for D in [min, max]
		const int xmin = static_cast<int>(std::floor(xl + doffs - o.max_disparity));
		const int xmax = static_cast<int>(std::ceil(xl + doffs - o.min_disparity));
		const TBest b = bestOnRow(left, xl, y, right, rowsR, o.row_tolerance, xmin, xmax, r);
		if (b.x < 0 || b.s1 < o.min_zncc) return std::nullopt;
		if (b.s2 > -2.f && (1.0 - b.s1) > o.max_ambiguity * (1.0 - b.s2)) return std::nullopt;
		// Dense refinement on the left row around the candidate corner: climb to
		// the local maximum, then fit a parabola.
		int x = b.x;
		float c0 = 0, cm = 0, cp = 0;
		if (!climbToPeak(left, xl, y, right, r, x, c0, cm, cp) || c0 < o.min_zncc) return std::nullopt;
		const float uR =
			refineRowShift(left, xl, y, right, x + parabolaPeak(cm, c0, cp), r, o.subpixel_iterations);
		const double D = calib.disparity(xl, uR);
		if (D < o.min_disparity || D > o.max_disparity) return std::nullopt;
		if (o.min_zncc_shifted > -1 && !silhouetteAgrees(xl, x, y)) return std::nullopt;
		// Left-right consistency: the right position's best left corner must be this one.
		const int xlmin = static_cast<int>(std::floor(x - doffs + o.min_disparity));
		const int xlmax = static_cast<int>(std::ceil(x - doffs + o.max_disparity));
		const TBest back = bestOnRow(right, x, y, left, rowsL, o.row_tolerance, xlmin, xlmax, r);
		if (back.x < 0 || std::abs(back.x - xl) > o.lr_tolerance_px) return std::nullopt;
		if (o.dense_check && !denseAgrees(xl, x, y, xmin, xmax)) return std::nullopt;
		return TMatch{uR, c0};
	}

	/** Windows beside the patch (disjoint from it: shift 2r+1) at the same
	 * disparity must correlate too. Near-flat windows carry no evidence and
	 * are skipped. */
	bool silhouetteAgrees(int xl, int x, int y) const
	{
		const int r = o.patch_radius, W = left.cols, sh = 2 * r + 1;
		const int sx[4] = {-sh, sh, 0, 0}, sy[4] = {0, 0, -sh, sh};
		for (int k = 0; k < 4; k++)
		{
			const int xa = xl + sx[k], xb = x + sx[k], yy = y + sy[k];
			if (xa - r < 0 || xa + r >= W || xb - r < 0 || xb + r >= W || yy - r < 0 || yy + r >= left.rows) continue;
			if (patchStd(left, xa, yy, r) < 3.0) continue;
			if (zncc(left, xa, yy, right, xb, yy, r) < o.min_zncc_shifted) return false;
		}
		return true;
	}

	/** Every integer shift of the range, not only the right corners: the
	 * dense maximum must be this match (+-1 px), and no other local maximum
	 * may pass the ambiguity bound. A right corner missing at the true
	 * position otherwise lets a look-alike win. */
	bool denseAgrees(int xl, int x, int y, int xmin, int xmax)
	{
		const int r = o.patch_radius, W = left.cols;
		const int x0 = std::max(xmin, r + 1), x1 = std::min(xmax, W - r - 2);
		denseRowZncc(left, xl, y, right, rightStats, x0, x1, r, dense, denseAcc);
		const int bi = argMax(dense);
		if (bi < 0 || std::abs(x0 + bi - x) > 1) return false;
		float s2 = -1.f;
		const int nd = static_cast<int>(dense.size());
		for (int k = 0; k < nd; k++)
			if (std::abs(k - bi) > 1 && (k == 0 || dense[k] >= dense[k - 1]) && (k + 1 == nd || dense[k] >= dense[k + 1]))
				s2 = std::max(s2, dense[k]);
		if ((1.0 - dense[bi]) > o.max_ambiguity * (1.0 - s2)) return false;
		return !o.shifted_window_check || shiftedWindowsAgree(xl, x, y, x0, x1);
	}

	/** Shiftable windows (Fusiello et al. 1997; Hirschmueller et al. 2002):
	 * the four windows holding the corner pixel at one of their corners. At a
	 * depth edge one of them lies on the pixel's own surface; if any textured
	 * one prefers another shift, the pixel's disparity is in doubt (typically
	 * a background pixel whose centred window is dominated by a foreground
	 * edge). */
	bool shiftedWindowsAgree(int xl, int x, int y, int x0, int x1)
	{
		const int r = o.patch_radius, W = left.cols;
		const int ox[4] = {-r, r, -r, r}, oy[4] = {-r, -r, r, r};
		for (int k = 0; k < 4; k++)
		{
			const int xa = xl + ox[k], ya = y + oy[k];
			if (xa - r < 0 || xa + r >= W || ya - r < 0 || ya + r >= left.rows) continue;
			if (patchStd(left, xa, ya, r) < 3.0) continue;  // no evidence either way
			const int a0 = std::max(x0 + ox[k], r + 1), a1 = std::min(x1 + ox[k], W - r - 2);
			if (x + ox[k] < a0 || x + ox[k] > a1) continue;
			denseRowZncc(left, xa, ya, right, rightStats, a0, a1, r, dense, denseAcc);
			const int b = argMax(dense), c = x + ox[k] - a0;
			if (b < 0) continue;
			float sm = dense[c];
			if (c > 0) sm = std::max(sm, dense[c - 1]);
			if (c + 1 < static_cast<int>(dense.size())) sm = std::max(sm, dense[c + 1]);
			if (std::abs(b - c) > 1 && dense[b] > sm + o.shifted_window_margin) return false;
		}
		return true;
	}
};
}  // namespace

void StereoFeatureExtractor::process(
	const cv::Mat& leftIn, const cv::Mat& rightIn, const geometry::TStereoCalib& calib,
	TStereoFrame& out) const
{
	if (leftIn.type() != CV_8UC1 || rightIn.type() != CV_8UC1 || leftIn.size() != rightIn.size() ||
		leftIn.empty())
		throw std::invalid_argument(
			"StereoFeatureExtractor: needs two non-empty CV_8UC1 images of equal size");
	const auto& o = m_opts;
	out.meas.clear();
	auto t0 = Clock::now();
	cv::Mat left = leftIn, right = rightIn;
	if (o.presmooth_sigma > 0)
	{
		cv::GaussianBlur(leftIn, left, cv::Size(), o.presmooth_sigma);
		cv::GaussianBlur(rightIn, right, cv::Size(), o.presmooth_sigma);
	}
	out.left = left;  // what the patches come from: later frames correlate against this
	out.right = right;
	const int r = o.patch_radius;
	const int borderR = r + 3;
	std::vector<cv::KeyPoint> kl, kr;
	m_corners.detect(left, o.max_per_cell, m_corners.border(), kl);
	m_corners.detect(right, o.max_per_cell_right, borderR, kr, CornerUse::Candidates);
	out.cornersLeft = kl.size();
	out.cornersRight = kr.size();
	out.timings.detect_ms = msSince(t0);

	t0 = Clock::now();
	RowIndex rowsR, rowsL;
	rowsR.build(kr, right.rows);
	rowsL.build(kl, left.rows);
	// Scratch reused across frames (one per thread: the channels may run in parallel).
	thread_local TRightWindowStats rightStats;
	if (o.dense_check) rightStats.reset(right, r);
	TCornerMatcher matcher{o, calib, left, right, rowsR, rowsL, rightStats, {}, {}};
	std::vector<TPair> pairs;
	pairs.reserve(kl.size());
	for (size_t i = 0; i < kl.size(); i++)
		if (const auto m = matcher.match(kl[i])) pairs.push_back({static_cast<int>(i), m->uR, m->s});
	out.timings.stereo_ms = msSince(t0);

	t0 = Clock::now();
	std::vector<cv::KeyPoint> matched;
	matched.reserve(pairs.size());
	for (const auto& p : pairs) matched.push_back(kl[p.kp]);
	std::vector<TBriefDescriptor> desc;
	std::vector<uint8_t> described;
	m_corners.describe(left, matched, desc, described, &out.smoothed);
	out.meas.reserve(pairs.size());
	const int ph = kPatchSize / 2;
	for (size_t i = 0; i < pairs.size(); i++)
	{
		const auto& p = pairs[i];
		const auto& k = kl[p.kp];
		if (!described[i]) continue;
		TStereoMeasurement m;
		m.uL = std::floor(k.pt.x);
		m.v = std::floor(k.pt.y);
		m.uR = p.uR;
		m.response = k.response;
		m.zncc = p.s;
		Eigen::Matrix3d J;
		if (!calib.triangulate(m.uL, m.v, m.uR, m.P, &J) || m.P.z() > o.max_depth) continue;
		m.cov = calib.triangulationCovariance(J, o.sigma_px);
		m.desc = desc[i];
		for (int dy = -ph; dy <= ph; dy++)
		{
			const uint8_t* row = left.ptr<uint8_t>(static_cast<int>(m.v) + dy) + static_cast<int>(m.uL) - ph;
			std::copy(row, row + kPatchSize, m.patch.begin() + (dy + ph) * kPatchSize);
		}
		out.meas.push_back(m);
	}
	out.timings.describe_ms = msSince(t0);
}


namespace
{
/** A template's own sums, the same at every position it is scored. */
struct TTemplateSums
{
	int s = 0;
	int64_t ss = 0;
};

TTemplateSums templateSums(const std::array<uint8_t, kPatchSize * kPatchSize>& p)
{
	TTemplateSums t;
	for (const uint8_t a : p)
	{
		t.s += a;
		t.ss += a * a;
	}
	return t;
}

float patchZncc(
	const std::array<uint8_t, kPatchSize * kPatchSize>& p, const TTemplateSums& t, const cv::Mat& img, int x, int y)
{
	constexpr int N = kPatchSize, h = N / 2;
	int sb = 0;
	int64_t sbb = 0, sab = 0;
	for (int dy = 0; dy < N; dy++)
	{
		const uint8_t* row = img.ptr<uint8_t>(y - h + dy) + x - h;
		const uint8_t* pr = p.data() + dy * N;
		for (int dx = 0; dx < N; dx++)
		{
			const int a = pr[dx], b = row[dx];
			sb += b;
			sbb += b * b;
			sab += a * b;
		}
	}
	const double n = N * N;
	const double va = t.ss - double(t.s) * t.s / n, vb = sbb - double(sb) * sb / n;
	if (va < 1e-6 || vb < 1e-6) return -1.f;
	return static_cast<float>((sab - double(t.s) * sb / n) / std::sqrt(va * vb));
}
}  // namespace

float patchZncc(const std::array<uint8_t, kPatchSize * kPatchSize>& p, const cv::Mat& img, int x, int y)
{
	return patchZncc(p, templateSums(p), img, x, y);
}

bool locatePatch(
	const std::array<uint8_t, kPatchSize * kPatchSize>& patch, const cv::Mat& img, int x0, int y0, int radius_px,
	float min_zncc, int iterations, float& xOut, float& yOut)
{
	const int ph = kPatchSize / 2;
	const auto inside = [&](int xx, int yy) {
		return xx - ph - 1 >= 0 && yy - ph - 1 >= 0 && xx + ph + 1 < img.cols && yy + ph + 1 < img.rows;
	};
	int x = x0, y = y0;
	float c[3][3];
	bool peak = false;
	// The climb stays within radius_px + 1 of the start: each position is
	// scored once (neighbouring steps share up to six of their nine).
	const TTemplateSums sums = templateSums(patch);
	const int side = 2 * radius_px + 3;
	thread_local std::vector<float> scored;
	scored.assign(size_t(side) * side, std::numeric_limits<float>::quiet_NaN());
	const auto score = [&](int px, int py) {
		float& v = scored[size_t(py - y0 + radius_px + 1) * side + size_t(px - x0 + radius_px + 1)];
		if (std::isnan(v)) v = patchZncc(patch, sums, img, px, py);
		return v;
	};
	for (int step = 0; step <= radius_px && inside(x, y); step++)
	{
		// All nine scores first, then the arg-max: comparing against the
		// centre before it is computed read an uninitialised value.
		for (int dy = -1; dy <= 1; dy++)
			for (int dx = -1; dx <= 1; dx++) c[dy + 1][dx + 1] = score(x + dx, y + dy);
		int bx = 0, by = 0;
		for (int dy = -1; dy <= 1; dy++)
			for (int dx = -1; dx <= 1; dx++)
				if (c[dy + 1][dx + 1] > c[by + 1][bx + 1]) bx = dx, by = dy;
		if (bx == 0 && by == 0)
		{
			peak = true;
			break;
		}
		if (step == radius_px) break;
		x += bx;
		y += by;
	}
	if (!peak || c[1][1] < min_zncc) return false;
	float xs = x + parabolaPeak(c[1][0], c[1][1], c[1][2]);
	float ys = y + parabolaPeak(c[0][1], c[1][1], c[2][1]);
	// The parabola locks towards integer pixels; Gauss-Newton on the
	// interpolated image does not.
	float xr, yr;
	if (refinePatch2D(patch.data(), kPatchSize, img, xs, ys, iterations, xr, yr)) xs = xr, ys = yr;
	xOut = xs;
	yOut = ys;
	return true;
}

}  // namespace shadyloc::features
