/* ShadyLoc — the keyframe matcher (stereo VO stage, reused by the localisers). */
#include <shadyloc/vo/KeyframeMatcher.h>

#include <shadyloc/features/PatchWarp.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <optional>
#include <cmath>
#include <stdexcept>

namespace shadyloc::vo
{
namespace
{

/** Uniform grid over the current measurements for region queries. */
struct MeasGrid
{
	static constexpr int kCell = 16;
	int cols = 0, rows = 0;
	std::vector<std::vector<int>> cells;
	void build(const std::vector<features::TStereoMeasurement>& m, int W, int H)
	{
		cols = (W + kCell - 1) / kCell;
		rows = (H + kCell - 1) / kCell;
		cells.assign(static_cast<size_t>(cols * rows), {});
		for (size_t i = 0; i < m.size(); i++)
			cells[static_cast<int>(m[i].v) / kCell * cols + static_cast<int>(m[i].uL) / kCell].push_back(
				static_cast<int>(i));
	}
};

Eigen::Matrix3d skew(const Eigen::Vector3d& v)
{
	Eigen::Matrix3d S;
	S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
	return S;
}

void checkInput(const TKeyframeMatchInput& in)
{
	if (!in.landmarks || !in.frame)
		throw std::invalid_argument("KeyframeMatcher: input without landmarks or frame");
	if (in.frame->left.type() != CV_8UC1 || in.frame->left.empty())
		throw std::invalid_argument("KeyframeMatcher: the frame's left image must be a non-empty CV_8UC1");
	if (in.taken && in.taken->size() != in.frame->meas.size())
		throw std::invalid_argument("KeyframeMatcher: the taken mask must have one entry per current measurement");
}

/** Where is landmark lm's patch in img near (x0, y0): through the warp A
 * when given (features/PatchWarp.h), else as it is. */
bool locateLandmark(
	const features::TStereoMeasurement& lm, const cv::Mat& img, int x0, int y0, const Eigen::Matrix2d* A, int radius,
	float minZncc, int iterations, float& x, float& y)
{
	return A ? features::locateWarpedPatch(lm.patch, img, x0, y0, *A, radius, minZncc, iterations, x, y)
			 : features::locatePatch(lm.patch, img, x0, y0, radius, minZncc, iterations, x, y);
}

/** The correspondence of landmark lm with the current measurement z_curr
 * (uL, v, uR); false when z_curr does not triangulate. */
bool correspondenceOf(
	const features::TStereoMeasurement& lm, const TKeyframeMatchInput& in, const Eigen::Vector3d& z_curr,
	geometry::TStereoCorrespondence& k)
{
	k.P_ref = lm.P;
	k.cov_ref = lm.cov;
	k.z_ref = Eigen::Vector3d(lm.uL, lm.v, lm.uR);
	k.sigma_disparity_ref = lm.sigma_d;
	k.calib_ref = in.calib_kf;
	k.z_curr = z_curr;
	return in.calib.triangulate(z_curr.x(), z_curr.y(), z_curr.z(), k.P_curr);
}
}  // namespace

KeyframeMatcher::KeyframeMatcher(const TOptions& o) : m_opts(o) {}

bool KeyframeMatcher::warpOf(
	const TKeyframeMatchInput& in, const features::TStereoMeasurement& lm, Eigen::Matrix2d& A) const
{
	if (!m_opts.warp || lm.normal.isZero()) return false;
	return features::planeInducedAffine(
			   in.calib_kf, in.calib, in.T_curr_kf_pred, lm.P, lm.normal.cast<double>(), A) &&
		   features::warpDistortion(A) > m_opts.warp_min_distortion;
}

TPredictedMeasurement KeyframeMatcher::predict(
	const geometry::TStereoCalib& calib, const Eigen::Isometry3d& T_curr_kf, const geometry::Matrix6d& cov_T,
	const Eigen::Vector3d& P_kf, const Eigen::Matrix3d& cov_P, double sigma_px)
{
	TPredictedMeasurement pm;
	const Eigen::Vector3d p = T_curr_kf * P_kf;
	if (p.z() < 0.1) return pm;
	Eigen::Matrix3d Jp;
	pm.z = calib.project(p, &Jp);
	// z = project(exp(xi) T P): dz/dP = Jp R, dz/dxi = Jp [I, -[p]x] (geometry::stereoResidual).
	const Eigen::Matrix3d JP = Jp * T_curr_kf.linear();
	geometry::Matrix36d Jxi;
	Jxi.leftCols<3>() = Jp;
	Jxi.rightCols<3>() = -Jp * skew(p);
	pm.S = JP * cov_P * JP.transpose() + Jxi * cov_T * Jxi.transpose() +
		   sigma_px * sigma_px * Eigen::Matrix3d::Identity();
	pm.ok = pm.S.allFinite();
	return pm;
}

Eigen::Matrix3d KeyframeMatcher::gateMatrix(const Eigen::Matrix3d& S) const
{
	return gateMatrix(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(0.5 * (S + S.transpose())));
}

Eigen::Matrix3d KeyframeMatcher::gateMatrix(const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>& es) const
{
	// An axis of {r : r^T G^-1 r <= chi2} has half-length sqrt(chi2 lambda).
	const double chi2 = m_opts.gate_chi2;
	const double lo = m_opts.gate_min_px * m_opts.gate_min_px / chi2;
	const double maxPx = std::max(m_opts.gate_max_px, m_opts.gate_landmark_max_px);
	const double hi = maxPx * maxPx / chi2;
	const Eigen::Vector3d lam = es.eigenvalues().cwiseMax(lo).cwiseMin(hi);
	return es.eigenvectors() * lam.asDiagonal() * es.eigenvectors().transpose();
}

int KeyframeMatcher::searchDescriptors(
	const TKeyframeMatchInput& in, double radius, std::vector<int>& matchOf, TGateStats* gateStats) const
{
	checkInput(in);
	const auto& o = m_opts;
	const auto& kfm = *in.landmarks;
	const auto& meas = in.frame->meas;
	const auto& calib = in.calib;
	MeasGrid grid;
	grid.build(meas, in.frame->left.cols, in.frame->left.rows);
	matchOf.assign(kfm.size(), -1);
	std::vector<int> bestKf(meas.size(), -1), bestD(meas.size(), 999);
	const bool gate = o.region == SearchRegion::Gate;
	const double r2 = radius * radius;
	std::vector<double> axes;
	int overflow = 0, tooUncertain = 0;
	const bool splitCeiling = gate && o.gate_landmark_max_px > 0;
	auto axisOf = [&](const Eigen::Vector3d& eigenvalues) {
		return std::sqrt(o.gate_chi2 * std::max(0.0, eigenvalues.maxCoeff()));
	};
	auto longestAxis = [&](const Eigen::Matrix3d& S) {
		return axisOf(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(0.5 * (S + S.transpose()), Eigen::EigenvaluesOnly)
						  .eigenvalues());
	};
	const double W = in.frame->left.cols, H = in.frame->left.rows;
	for (size_t j = 0; j < kfm.size(); j++)
	{
		double u = 0, v = 0, hu = radius, hv = radius;
		Eigen::Vector3d zp = Eigen::Vector3d::Zero();
		Eigen::Matrix3d Ginv = Eigen::Matrix3d::Zero();
		if (gate)
		{
			const auto pm = predict(calib, in.T_curr_kf_pred, in.cov_T_curr_kf_pred, kfm[j].P, kfm[j].cov, o.sigma_px);
			if (!pm.ok) continue;
			// One decomposition for the gate and its axis (the eigenvalues are
			// the same whether the vectors are computed or not).
			const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (pm.S + pm.S.transpose()));
			if (pm.z.x() >= 0 && pm.z.x() < W && pm.z.y() >= 0 && pm.z.y() < H)
			{
				// The longest axis of the unclamped gate: sqrt(chi2 lambda_max).
				const double axis = axisOf(es.eigenvalues());
				axes.push_back(axis);
				// The ceiling on the prediction's part only (see gate_landmark_max_px).
				const double predAxis = splitCeiling ? longestAxis(predict(
														   calib, in.T_curr_kf_pred, in.cov_T_curr_kf_pred, kfm[j].P,
														   Eigen::Matrix3d::Zero(), o.sigma_px)
															   .S)
													 : axis;
				if (predAxis > o.gate_max_px)
				{
					overflow++;
					if (!o.gate_clamp) continue;
				}
				else if (splitCeiling && axis > o.gate_landmark_max_px)
				{
					tooUncertain++;
					if (!o.gate_clamp) continue;
				}
			}
			const Eigen::Matrix3d G = gateMatrix(es);
			Ginv = G.inverse();
			zp = pm.z;
			u = zp.x();
			v = zp.y();
			// The ellipsoid's extent along uL and v: the search box.
			hu = std::sqrt(o.gate_chi2 * G(0, 0));
			hv = std::sqrt(o.gate_chi2 * G(1, 1));
		}
		else
		{
			const Eigen::Vector3d p = in.T_curr_kf_pred * kfm[j].P;
			if (p.z() < 0.1) continue;
			u = calib.fx * p.x() / p.z() + calib.cx;
			v = calib.fy * p.y() / p.z() + calib.cy;
		}
		const int c0 = std::max(0, static_cast<int>((u - hu) / MeasGrid::kCell));
		const int c1 = std::min(grid.cols - 1, static_cast<int>((u + hu) / MeasGrid::kCell));
		const int r0 = std::max(0, static_cast<int>((v - hv) / MeasGrid::kCell));
		const int r1 = std::min(grid.rows - 1, static_cast<int>((v + hv) / MeasGrid::kCell));
		int b1 = 999, b2 = 999, bi = -1;
		// Through the landmark's warp, the candidates' descriptors are made
		// again with the warped tests (features/PatchWarp.h), built at the
		// first candidate inside the gate (a gate may hold none).
		std::optional<features::WarpedBriefPattern> warped;
		bool warpChecked = false;
		const auto warpedPattern = [&]() -> const features::WarpedBriefPattern* {
			if (!warpChecked)
			{
				warpChecked = true;
				Eigen::Matrix2d A;
				// BRIEF tests only: ORB's are oriented, and a map says which it holds.
				if (in.brief && !in.frame->smoothed.empty() && warpOf(in, kfm[j], A)) warped.emplace(*in.brief, A);
			}
			return warped ? &*warped : nullptr;
		};
		features::TBriefDescriptor wd;
		for (int rr = r0; rr <= r1; rr++)
			for (int cc = c0; cc <= c1; cc++)
				for (int i : grid.cells[rr * grid.cols + cc])
				{
					const auto& m = meas[i];
					if (gate)
					{
						const Eigen::Vector3d r = Eigen::Vector3d(m.uL, m.v, m.uR) - zp;
						if (r.dot(Ginv * r) > o.gate_chi2) continue;
					}
					else
					{
						const double du = m.uL - u, dv = m.v - v;
						if (du * du + dv * dv > r2) continue;
					}
					const auto* wp = warpedPattern();
					const int d = !wp ? features::hamming(kfm[j].desc, m.desc)
									  : wp->compute(in.frame->smoothed, static_cast<int>(m.uL), static_cast<int>(m.v), wd)
										  ? features::hamming(kfm[j].desc, wd)
										  : 999;
					if (d < b1)
					{
						b2 = b1;
						b1 = d;
						bi = i;
					}
					else if (d < b2)
						b2 = d;
				}
		if (bi < 0 || b1 > o.max_hamming || (b2 < 999 && b1 >= o.match_ratio * b2)) continue;
		// One keyframe landmark per current measurement: keep the closest descriptor.
		if (b1 < bestD[bi])
		{
			if (bestKf[bi] >= 0) matchOf[bestKf[bi]] = -1;
			bestD[bi] = b1;
			bestKf[bi] = static_cast<int>(j);
			matchOf[j] = bi;
		}
	}
	if (gateStats)
	{
		*gateStats = TGateStats();
		gateStats->predicted = static_cast<int>(axes.size());
		gateStats->overflow = overflow;
		gateStats->too_uncertain = tooUncertain;
		if (!axes.empty())
		{
			std::nth_element(axes.begin(), axes.begin() + axes.size() / 2, axes.end());
			gateStats->median_axis_px = axes[axes.size() / 2];
		}
	}
	return static_cast<int>(std::count_if(matchOf.begin(), matchOf.end(), [](int i) { return i >= 0; }));
}

void KeyframeMatcher::searchPatches(
	const TKeyframeMatchInput& in, const std::vector<uint8_t>& skip, cv::Mat& occupied, TKeyframeMatchOutput& out) const
{
	checkInput(in);
	const auto& o = m_opts;
	const auto& kfm = *in.landmarks;
	const auto& fr = *in.frame;
	if (fr.right.empty() || skip.size() != kfm.size() || occupied.size() != fr.left.size() || occupied.type() != CV_8UC1)
		throw std::invalid_argument("KeyframeMatcher::searchPatches: no right image, or skip/occupied of the wrong size");
	const int margin = features::kPatchSize + o.patch_search_radius_px + 8;
	for (size_t j = 0; j < kfm.size(); j++)
	{
		if (skip[j]) continue;
		const Eigen::Vector3d p = in.T_curr_kf_pred * kfm[j].P;
		if (p.z() < 0.5) continue;
		const Eigen::Vector3d z = in.calib.project(p);
		const int x0 = static_cast<int>(std::lround(z.x())), y0 = static_cast<int>(std::lround(z.y()));
		if (x0 < margin || y0 < margin || x0 >= fr.left.cols - margin || y0 >= fr.left.rows - margin) continue;
		Eigen::Matrix2d A;
		const bool warped = warpOf(in, kfm[j], A);
		float xs, ys;
		if (!locateLandmark(
				kfm[j], fr.left, x0, y0, warped ? &A : nullptr, o.patch_search_radius_px,
				static_cast<float>(o.patch_min_zncc), o.refine_iterations, xs, ys))
			continue;
		const int xi = static_cast<int>(std::lround(xs)), yi = static_cast<int>(std::lround(ys));
		if (xi < 0 || yi < 0 || xi >= occupied.cols || yi >= occupied.rows || occupied.at<uint8_t>(yi, xi)) continue;
		// The column in the right image: the predicted disparity carried to
		// the found pixel, refined along the row.
		float uR;
		if (!features::matchAlongRow(
				fr.left, xi, yi, fr.right, static_cast<float>(xi - (z.x() - z.z())), o.patch_stereo_range_px, 3,
				static_cast<float>(o.patch_stereo_min_zncc), o.refine_iterations, uR))
			continue;
		geometry::TStereoCorrespondence k;
		if (!correspondenceOf(kfm[j], in, Eigen::Vector3d(xs, ys, uR + (xs - xi)), k)) continue;
		occupied.at<uint8_t>(yi, xi) = 1;
		out.corr.push_back(k);
		out.warped += warped;
		out.landmark.push_back(static_cast<int>(j));
		out.measurement.push_back(-1);
	}
}

void KeyframeMatcher::match(const TKeyframeMatchInput& in, TKeyframeMatchOutput& out) const
{
	checkInput(in);
	const auto& o = m_opts;
	const auto& kfm = *in.landmarks;
	const auto& fr = *in.frame;
	const auto& calib = in.calib;
	out = TKeyframeMatchOutput();
	std::vector<int> matchOf;
	int nMatch = 0;
	if (o.region == SearchRegion::Gate)
		nMatch = searchDescriptors(in, 0.0, matchOf, &out.gate);
	else
	{
		nMatch = searchDescriptors(in, in.wide ? o.search_radius_lost_px : o.search_radius_px, matchOf);
		if (nMatch < o.min_matches && !in.wide)
		{
			nMatch = searchDescriptors(in, o.search_radius_lost_px, matchOf);
			out.widened = true;
		}
	}
	out.descriptor_matches = nMatch;

	// Sub-pixel refinement: where is the keyframe's patch in this image?
	out.corr.reserve(nMatch);
	const cv::Mat& img = fr.left;
	for (size_t j = 0; j < kfm.size(); j++)
	{
		if (matchOf[j] < 0 || (in.taken && (*in.taken)[static_cast<size_t>(matchOf[j])])) continue;
		const auto& m = fr.meas[matchOf[j]];
		float xs, ys;
		Eigen::Matrix2d A;
		const bool warped = warpOf(in, kfm[j], A);
		const int x0 = static_cast<int>(m.uL), y0 = static_cast<int>(m.v);
		if (!locateLandmark(
				kfm[j], img, x0, y0, warped ? &A : nullptr, o.refine_radius, o.refine_min_zncc, o.refine_iterations, xs,
				ys))
			continue;
		// The disparity measured at the corner carries over to the refined position.
		geometry::TStereoCorrespondence k;
		if (!correspondenceOf(kfm[j], in, Eigen::Vector3d(xs, ys, m.uR + static_cast<double>(xs - m.uL)), k)) continue;
		out.corr.push_back(k);
		out.warped += warped;
		out.landmark.push_back(static_cast<int>(j));
		out.measurement.push_back(matchOf[j]);
	}
	if (o.near_min_disparity > 0)
	{
		// Near landmarks only, if there are enough of them (TStereoVOOptions::near_min_disparity).
		const double fb = calib.fx * calib.baseline;
		size_t n = 0;
		for (const auto& k : out.corr) n += fb / k.P_ref.z() >= o.near_min_disparity;
		if (static_cast<int>(n) >= o.near_min_matches)
		{
			size_t w = 0;
			for (size_t i = 0; i < out.corr.size(); i++)
				if (fb / out.corr[i].P_ref.z() >= o.near_min_disparity)
				{
					out.corr[w] = out.corr[i];
					out.landmark[w] = out.landmark[i];
					out.measurement[w] = out.measurement[i];
					w++;
				}
			out.corr.resize(w);
			out.landmark.resize(w);
			out.measurement.resize(w);
			out.near_only = true;
		}
	}
}

}  // namespace shadyloc::vo
