/* ShadyLoc — calibrating the invariant transform from data (see header and
 * docs/calibration.md). */
#include <shadyloc/image/InvariantCalibration.h>
#include <shadyloc/image/ShadowMetrics.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>

namespace shadyloc::image
{
namespace
{
// Grey levels of the default scale per unit of I: the shadow metric's floor
// of one grey level (ShadowStep::relative()) then means what it means for
// the 8-bit channel.
constexpr double kGreyPerLog = 255.0;

std::array<float, 256> logTable(const TCalibrationInput& in)
{
	std::array<float, 256> t{};
	for (int v = 0; v < 256; v++) t[v] = float(std::log(linearise(v, in.linearisation, in.gamma)));
	return t;
}

void requireColour(const cv::Mat& m, const std::string& what)
{
	if (m.empty()) throw std::invalid_argument(what + ": empty image");
	if (m.type() != CV_8UC3)
		throw std::invalid_argument(
			what + ": expected an 8-bit 3-channel colour image, got " + std::to_string(m.channels()) +
			" channel(s), depth " + std::to_string(m.depth()));
}

bool trusted(const uint8_t* px, const TCalibrationInput& in)
{
	for (int c = 0; c < 3; c++)
		if (px[c] < in.minCode || px[c] >= in.maxCode) return false;
	return true;
}

/** One point's log-chromaticities under both lights: pixel a, then pixel b. */
void addChange(
	TChromaChanges& it, const uint8_t* a, const uint8_t* b, const std::array<float, 256>& L, const ChannelIndices& ci)
{
	it.xa.push_back(L[a[ci.b]] - L[a[ci.r]]), it.ya.push_back(L[a[ci.g]] - L[a[ci.r]]);
	it.xb.push_back(L[b[ci.b]] - L[b[ci.r]]), it.yb.push_back(L[b[ci.g]] - L[b[ci.r]]);
}

// Quantile q in [0,1] of v (v is reordered).
double quantile(std::vector<float>& v, double q)
{
	if (v.empty()) return 0;
	const size_t k = std::min(v.size() - 1, size_t(std::llround(q * double(v.size() - 1))));
	std::nth_element(v.begin(), v.begin() + long(k), v.end());
	return v[k];
}

// Refines the grid minimum by a least-squares parabola through the curve
// within +-halfWidth of it (at least the minimum and its two neighbours).
// A wider window averages out the curve's small-scale roughness (medians of
// a few thousand pixels move in steps as alpha changes), so the estimate does
// not depend on the grid step. Falls back to the grid minimum where the fit
// is not convex or its vertex leaves the window.
double refinedArgmin(const std::vector<double>& a, const std::vector<double>& c, double halfWidth)
{
	const size_t i = size_t(std::min_element(c.begin(), c.end()) - c.begin());
	if (i == 0 || i + 1 >= c.size()) return a[i];
	size_t lo = i - 1, hi = i + 1;
	while (lo > 0 && a[i] - a[lo - 1] <= halfWidth + 1e-12) lo--;
	while (hi + 1 < c.size() && a[hi + 1] - a[i] <= halfWidth + 1e-12) hi++;
	// Fit c = p0 + p1 t + p2 t^2 in t = (a - a[i]) / h, scaled to [-1, 1]
	// for a well-conditioned 3x3 normal system.
	const double h = std::max(a[hi] - a[i], a[i] - a[lo]);
	double S[5] = {0, 0, 0, 0, 0}, T[3] = {0, 0, 0};
	for (size_t k = lo; k <= hi; k++)
	{
		const double t = (a[k] - a[i]) / h;
		double tp = 1;
		for (int e = 0; e < 5; e++)
		{
			if (e < 3) T[e] += tp * c[k];
			S[e] += tp;
			tp *= t;
		}
	}
	const cv::Matx33d A(S[0], S[1], S[2], S[1], S[2], S[3], S[2], S[3], S[4]);
	cv::Vec3d sol;
	if (!cv::solve(A, cv::Vec3d(T[0], T[1], T[2]), sol, cv::DECOMP_CHOLESKY) || !(sol[2] > 0)) return a[i];
	const double v = a[i] - h * sol[1] / (2 * sol[2]);
	if (!(v >= a[lo] && v <= a[hi])) return a[i];
	return v;
}

// Bootstrap over items for methods whose curve is the mean of per-item curves.
void bootstrapMeanCurve(const std::vector<std::vector<double>>& perItem, const TAlphaSearch& s, TAlphaCurve& out)
{
	const size_t n = perItem.size(), m = out.alpha.size();
	out.cost.assign(m, 0.0);
	for (const auto& c : perItem)
		for (size_t j = 0; j < m; j++) out.cost[j] += c[j] / double(n);
	out.best = refinedArgmin(out.alpha, out.cost, s.refineHalfWidth);
	out.ciLow = out.ciHigh = out.best;
	out.bootstrapRounds = s.bootstrapRounds;
	if (s.bootstrapRounds <= 0 || n < 2) return;
	std::mt19937 rng(s.seed);
	std::uniform_int_distribution<size_t> pick(0, n - 1);
	std::vector<float> bests;
	std::vector<double> cost(m);
	for (int r = 0; r < s.bootstrapRounds; r++)
	{
		std::fill(cost.begin(), cost.end(), 0.0);
		for (size_t k = 0; k < n; k++)
		{
			const auto& c = perItem[pick(rng)];
			for (size_t j = 0; j < m; j++) cost[j] += c[j];
		}
		bests.push_back(float(refinedArgmin(out.alpha, cost, s.refineHalfWidth)));
	}
	out.ciLow = quantile(bests, 0.025);
	out.ciHigh = quantile(bests, 0.975);
}

// Per-item curve: the relative step (or its log) between values a and b of
// I = y - alpha x, on the grid.
std::vector<double> relativeStepCurve(
	const std::vector<float>& xa, const std::vector<float>& ya, const std::vector<float>& xb,
	const std::vector<float>& yb, const std::vector<double>& grid, bool logOf)
{
	std::vector<double> curve(grid.size()), va(xa.size()), vb(xa.size());
	for (size_t j = 0; j < grid.size(); j++)
	{
		const double al = grid[j];
		for (size_t i = 0; i < xa.size(); i++)
		{
			va[i] = kGreyPerLog * (ya[i] - al * xa[i]);
			vb[i] = kGreyPerLog * (yb[i] - al * xb[i]);
		}
		const double r = relativeShadowStepOfValues(va, vb).relative();
		curve[j] = logOf ? std::log(r) : r;
	}
	return curve;
}

// At most maxN elements by a regular stride (deterministic).
template <typename T>
void thin(std::vector<T>& v, size_t keepEvery)
{
	if (keepEvery <= 1) return;
	size_t k = 0;
	for (size_t i = 0; i < v.size(); i += keepEvery) v[k++] = v[i];
	v.resize(k);
}

constexpr size_t kMaxPixelsPerItem = 20000;	 // per pair: medians stay cheap, still tight
constexpr size_t kMinEntropySamples = 2000;
constexpr size_t kMinEdgeSamples = 200;
}  // namespace

// ---- options ---------------------------------------------------------------
void TCalibrationInput::validate() const
{
	auto bad = [](const std::string& f, const std::string& why) {
		throw std::invalid_argument("calibration input '" + f + "': " + why);
	};
	if (minCode < 0 || minCode > 254) bad("min_code", "must be in [0,254]");
	if (maxCode <= minCode || maxCode > 256) bad("max_code", "must be in (min_code, 256]");
	if (!(skipTopFraction >= 0 && skipTopFraction < 1)) bad("skip_top", "must be in [0,1)");
	if (stride < 1 || stride > 64) bad("stride", "must be in [1,64]");
	if (linearisation == Linearisation::Gamma && !(gamma > 0 && gamma < 10)) bad("gamma", "must be in (0,10)");
}

InvariantParams TCalibrationInput::params(double alpha) const
{
	auto p = InvariantParams::FromAlphaBeta(alpha, 1.0 - alpha);
	p.order = order;
	p.linearisation = linearisation;
	p.gamma = gamma;
	return p;
}

void TAlphaSearch::validate() const
{
	if (!(alphaMin >= 0 && alphaMin < alphaMax && alphaMax <= 1))
		throw std::invalid_argument("alpha search: need 0 <= alpha_min < alpha_max <= 1");
	if (!(step > 0 && step <= 0.5 * (alphaMax - alphaMin)))
		throw std::invalid_argument("alpha search: step must be in (0, (alpha_max - alpha_min)/2]");
	if (bootstrapRounds < 0 || bootstrapRounds > 100000)
		throw std::invalid_argument("alpha search: bootstrap rounds must be in [0, 100000]");
	if (!(refineHalfWidth >= 0 && refineHalfWidth <= 0.25))
		throw std::invalid_argument("alpha search: refine half-width must be in [0, 0.25]");
}

std::vector<double> TAlphaSearch::grid() const
{
	std::vector<double> g;
	const int n = int(std::floor((alphaMax - alphaMin) / step + 1e-9));
	for (int i = 0; i <= n; i++) g.push_back(alphaMin + step * i);
	return g;
}

double equivalentGreenPeak(double alpha, double l1, double l3)
{
	return 1.0 / (alpha / l1 + (1.0 - alpha) / l3);
}

// ---- 1. pairs ----------------------------------------------------------------
cv::Mat shadowMask(const TShadowPair& p, const TCalibrationInput& in, double minLogDrop, int erodeRadius)
{
	requireColour(p.free, "shadow pair '" + p.name + "' (free image)");
	requireColour(p.shadow, "shadow pair '" + p.name + "' (shadow image)");
	if (p.free.size() != p.shadow.size())
		throw std::invalid_argument("shadow pair '" + p.name + "': the two images differ in size");
	const auto L = logTable(in);
	cv::Mat mask(p.free.size(), CV_8U, cv::Scalar(0));
	const int top = int(in.skipTopFraction * p.free.rows);
	for (int y = top; y < p.free.rows; y++)
	{
		const uint8_t* f = p.free.ptr<uint8_t>(y);
		const uint8_t* s = p.shadow.ptr<uint8_t>(y);
		uint8_t* m = mask.ptr<uint8_t>(y);
		for (int x = 0; x < p.free.cols; x++)
		{
			const uint8_t* fp = f + 3 * x;
			const uint8_t* sp = s + 3 * x;
			if (!trusted(fp, in) || !trusted(sp, in)) continue;
			bool drop = true;
			for (int c = 0; c < 3 && drop; c++) drop = L[fp[c]] - L[sp[c]] > minLogDrop;
			m[x] = drop ? 255 : 0;
		}
	}
	if (erodeRadius > 0)
		cv::erode(
			mask, mask,
			cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * erodeRadius + 1, 2 * erodeRadius + 1)));
	return mask;
}

TAlphaCurve alphaFromShadowPairs(
	const std::vector<TShadowPair>& pairs, const TCalibrationInput& in, const TAlphaSearch& s,
	double minMaskFraction, std::vector<std::string>* skipped, PairAverage average)
{
	in.validate();
	s.validate();
	const bool geometric = average == PairAverage::Geometric;
	TAlphaCurve out;
	out.method = "pairs";
	out.costName = geometric ? "relative shadow step (geometric mean over pairs)"
							 : "relative shadow step (mean over pairs)";
	out.alpha = s.grid();
	const auto L = logTable(in);
	const auto ci = channelIndices(in.order);
	std::vector<std::vector<double>> perPair;
	for (const auto& p : pairs)
	{
		const cv::Mat mask = shadowMask(p, in);
		const double frac = cv::countNonZero(mask) / double(mask.total());
		if (frac < minMaskFraction || cv::countNonZero(mask) < 100)
		{
			if (skipped)
			{
				std::ostringstream m;
				m.precision(2);
				m << p.name << " (shadow mask " << std::fixed << 100 * frac << " % of the image)";
				skipped->push_back(m.str());
			}
			continue;
		}
		std::vector<float> xf, yf, xs, ys;
		for (int y = 0; y < mask.rows; y++)
		{
			const uint8_t* m = mask.ptr<uint8_t>(y);
			const uint8_t* f = p.free.ptr<uint8_t>(y);
			const uint8_t* sh = p.shadow.ptr<uint8_t>(y);
			for (int x = 0; x < mask.cols; x++)
				if (m[x])
				{
					const uint8_t* a = f + 3 * x;
					const uint8_t* b = sh + 3 * x;
					xf.push_back(L[a[ci.b]] - L[a[ci.r]]);
					yf.push_back(L[a[ci.g]] - L[a[ci.r]]);
					xs.push_back(L[b[ci.b]] - L[b[ci.r]]);
					ys.push_back(L[b[ci.g]] - L[b[ci.r]]);
				}
		}
		const size_t every = (xf.size() + kMaxPixelsPerItem - 1) / kMaxPixelsPerItem;
		thin(xf, every), thin(yf, every), thin(xs, every), thin(ys, every);
		perPair.push_back(relativeStepCurve(xf, yf, xs, ys, out.alpha, geometric));
	}
	if (perPair.empty())
		throw std::invalid_argument(
			"alpha from shadow pairs: no pair has a usable shadow mask (>= " + std::to_string(100 * minMaskFraction) +
			" % of the image darker by e^0.4 in every channel)");
	out.items = int(perPair.size());
	bootstrapMeanCurve(perPair, s, out);
	if (geometric)
		for (auto& c : out.cost) c = std::exp(c);  // report the geometric mean itself
	return out;
}

// ---- 2. entropy ----------------------------------------------------------------
TChromaSamples chromaSamples(const std::vector<cv::Mat>& images, const TCalibrationInput& in)
{
	in.validate();
	const auto L = logTable(in);
	const auto ci = channelIndices(in.order);
	TChromaSamples out;
	out.imageStart.push_back(0);
	for (size_t k = 0; k < images.size(); k++)
	{
		const cv::Mat& img = images[k];
		requireColour(img, "calibration image " + std::to_string(k));
		const int top = int(in.skipTopFraction * img.rows);
		for (int y = top; y < img.rows; y += in.stride)
		{
			const uint8_t* row = img.ptr<uint8_t>(y);
			for (int x = 0; x < img.cols; x += in.stride)
			{
				const uint8_t* px = row + 3 * x;
				if (!trusted(px, in)) continue;
				const float lr = L[px[ci.r]];
				out.x.push_back(L[px[ci.b]] - lr);
				out.y.push_back(L[px[ci.g]] - lr);
			}
		}
		out.imageStart.push_back(uint32_t(out.x.size()));
	}
	return out;
}

namespace
{
// Entropy (nats) of values v over their middle 90 %, bins by Scott's rule
// (Finlayson, Drew & Lu 2009), with exact quantiles. v is reordered.
double scottEntropySorted(std::vector<float>& v, std::vector<uint32_t>& hist)
{
	const size_t n = v.size();
	const size_t k05 = size_t(0.05 * double(n - 1)), k95 = size_t(0.95 * double(n - 1));
	std::nth_element(v.begin(), v.begin() + long(k05), v.end());
	const float lo = v[k05];
	std::nth_element(v.begin() + long(k05), v.begin() + long(k95), v.end());
	const float hi = v[k95];
	double sum = 0, sum2 = 0;
	for (size_t i = k05; i <= k95; i++) sum += v[i], sum2 += double(v[i]) * v[i];
	const double cnt = double(k95 - k05 + 1), mean = sum / cnt;
	const double sigma = std::sqrt(std::max(0.0, sum2 / cnt - mean * mean));
	const double width = 3.49 * sigma * std::pow(cnt, -1.0 / 3.0);
	if (!(width > 0) || !(hi > lo)) return 0.0;
	const int nb = std::clamp(int(std::ceil((hi - lo) / width)), 1, 8192);
	hist.assign(size_t(nb), 0);
	const float scale = float(nb / (double(hi) - lo));
	for (size_t i = k05; i <= k95; i++) hist[size_t(std::min(nb - 1, int((v[i] - lo) * scale)))]++;
	double H = 0;
	for (uint32_t c : hist)
		if (c > 0) H -= (c / cnt) * std::log(c / cnt);
	return H;
}

// The same entropy from one pass over the values: a fine histogram (kFine
// bins over [min, max]) gives the 5 % and 95 % quantiles (to a fine bin),
// the mean and sigma of the middle 90 % (bin centres), and Scott's bins are
// then merged from fine bins (each fine bin to the Scott bin holding its
// centre). Scott's bins are ~0.1 sigma wide for 50 000 values; a fine bin is
// (max - min) / 8192, so the quantiles and bin edges move by a small fraction
// of a bin (curves within 0.008 nats of the exact ones on the simulator and
// the UIUC images). Under half the CPU time of the partial sorts
// (bench_calibration).
double scottEntropyHistogram(const std::vector<float>& v, std::vector<uint32_t>& fine, std::vector<uint32_t>& hist)
{
	constexpr int kFine = 8192;
	const size_t n = v.size();
	// Eight independent running minima and maxima (one would be a chain of
	// dependent instructions; the compiler does not reorder float min/max).
	float mns[8], mxs[8];
	std::fill(mns, mns + 8, v[0]), std::fill(mxs, mxs + 8, v[0]);
	size_t i8 = 0;
	for (; i8 + 8 <= n; i8 += 8)
		for (int q = 0; q < 8; q++)
		{
			const float x = v[i8 + size_t(q)];
			mns[q] = x < mns[q] ? x : mns[q];
			mxs[q] = x > mxs[q] ? x : mxs[q];
		}
	for (; i8 < n; i8++) mns[0] = std::min(mns[0], v[i8]), mxs[0] = std::max(mxs[0], v[i8]);
	const float mn = *std::min_element(mns, mns + 8), mx = *std::max_element(mxs, mxs + 8);
	if (!(mx > mn)) return 0.0;
	const double fw = (double(mx) - mn) / kFine;  // fine bin width
	const float scale = float(1.0 / fw);
	fine.assign(kFine, 0);
	for (float x : v) fine[size_t(std::min(kFine - 1, int((x - mn) * scale)))]++;
	// Fine bins holding the values of rank k05 and k95.
	const size_t k05 = size_t(0.05 * double(n - 1)), k95 = size_t(0.95 * double(n - 1));
	int b05 = -1, b95 = -1;
	size_t cum = 0;
	for (int i = 0; i < kFine && b95 < 0; i++)
	{
		cum += fine[size_t(i)];
		if (b05 < 0 && cum > k05) b05 = i;
		if (cum > k95) b95 = i;
	}
	double cnt = 0, sum = 0, sum2 = 0;
	for (int i = b05; i <= b95; i++)
	{
		const double c = fine[size_t(i)], x = (i + 0.5) * fw;  // centre, relative to mn
		cnt += c, sum += c * x, sum2 += c * x * x;
	}
	const double mean = sum / cnt, sigma = std::sqrt(std::max(0.0, sum2 / cnt - mean * mean));
	const double width = 3.49 * sigma * std::pow(cnt, -1.0 / 3.0);
	const double lo = b05 * fw, hi = (b95 + 1) * fw;
	if (!(width > 0)) return 0.0;
	const int nb = std::clamp(int(std::ceil((hi - lo) / width)), 1, 8192);
	hist.assign(size_t(nb), 0);
	const double toCoarse = nb / (hi - lo);
	for (int i = b05; i <= b95; i++)
		hist[size_t(std::min(nb - 1, int(((i + 0.5) * fw - lo) * toCoarse)))] += fine[size_t(i)];
	double H = 0;
	for (uint32_t c : hist)
		if (c > 0) H -= (c / cnt) * std::log(c / cnt);
	return H;
}
}  // namespace

TAlphaCurve alphaByEntropy(const TChromaSamples& smp, const TAlphaSearch& s, EntropyQuantiles quantiles)
{
	s.validate();
	TAlphaCurve out;
	out.method = "entropy";
	out.costName = "entropy of the projected values (nats, mean over images)";
	out.alpha = s.grid();
	std::vector<std::vector<double>> perImage;
	std::vector<float> proj;
	std::vector<uint32_t> hist, fine;
	for (size_t k = 0; k < smp.images(); k++)
	{
		const size_t b = smp.imageStart[k], e = smp.imageStart[k + 1];
		if (e - b < kMinEntropySamples) continue;  // too few trusted pixels: no shape to measure
		std::vector<double> curve(out.alpha.size());
		proj.resize(e - b);
		for (size_t j = 0; j < out.alpha.size(); j++)
		{
			const float al = float(out.alpha[j]);
			for (size_t i = b; i < e; i++) proj[i - b] = smp.y[i] - al * smp.x[i];
			curve[j] = quantiles == EntropyQuantiles::Histogram ? scottEntropyHistogram(proj, fine, hist)
																: scottEntropySorted(proj, hist);
		}
		perImage.push_back(std::move(curve));
	}
	if (perImage.empty())
		throw std::invalid_argument(
			"alpha by entropy: no image has " + std::to_string(kMinEntropySamples) +
			" trusted pixels (too dark, saturated or small?)");
	out.items = int(perImage.size());
	bootstrapMeanCurve(perImage, s, out);
	return out;
}

// ---- 2b. edges -------------------------------------------------------------------
TEdgeSamples edgeSamples(const std::vector<cv::Mat>& images, const TCalibrationInput& in, int separation, double minLogEdge)
{
	in.validate();
	if (separation < 1 || separation > 64) throw std::invalid_argument("edge samples: separation must be in [1,64] px");
	const auto L = logTable(in);
	const auto ci = channelIndices(in.order);
	const float minEdge = float(minLogEdge);
	TEdgeSamples out;
	out.imageStart.push_back(0);
	const int st = in.stride, sep = separation;
	for (size_t k = 0; k < images.size(); k++)
	{
		const cv::Mat& img = images[k];
		requireColour(img, "calibration image " + std::to_string(k));
		const int top = int(in.skipTopFraction * img.rows);
		auto add = [&](const uint8_t* a, const uint8_t* b) {
			if (!trusted(a, in) || !trusted(b, in)) return;
			const float ab = L[a[ci.b]], ag = L[a[ci.g]], ar = L[a[ci.r]];
			const float bb = L[b[ci.b]], bg = L[b[ci.g]], br = L[b[ci.r]];
			const float dl = (bb + bg + br - ab - ag - ar) * (1.0f / 3.0f);
			if (std::abs(dl) < minEdge) return;
			out.dx.push_back((bb - br) - (ab - ar));
			out.dy.push_back((bg - br) - (ag - ar));
			out.dl.push_back(dl);
		};
		for (int y = top; y + sep < img.rows; y += st)
		{
			const uint8_t* row = img.ptr<uint8_t>(y);
			const uint8_t* below = img.ptr<uint8_t>(y + sep);
			for (int x = 0; x + sep < img.cols; x += st)
			{
				add(row + 3 * x, row + 3 * (x + sep));
				add(row + 3 * x, below + 3 * x);
			}
		}
		out.imageStart.push_back(uint32_t(out.dx.size()));
	}
	return out;
}

TAlphaCurve alphaByEdgeDirections(const TEdgeSamples& smp, const TAlphaSearch& s, double maxChromaPerBrightness)
{
	s.validate();
	if (!(maxChromaPerBrightness > 0))
		throw std::invalid_argument("alpha by edges: the chromaticity / brightness step bound must be > 0");
	const float maxRatio2 = float(std::min(1e6, maxChromaPerBrightness * maxChromaPerBrightness));
	TAlphaCurve out;
	out.method = "edges";
	out.costName = "-(density of edge directions at (1, alpha)), mean over images";
	out.alpha = s.grid();
	// Direction of the chromaticity step, signed so that it points the way
	// the brightness drops: across a shadow edge it is +(1, alpha) (darker =
	// bluer: x = log(B/R) rises, and y = log(G/R) with it by alpha).
	constexpr int kBins = 1440;	 // 0.25 degree
	constexpr double kBandwidth = 0.06;	 // kernel width (rad, ~3.4 degrees)
	constexpr float kMinChromaStep = 0.02f;	 // below: grey texture or noise, no direction
	std::vector<std::vector<double>> perImage;
	std::vector<double> hist(kBins);
	for (size_t k = 0; k < smp.images(); k++)
	{
		const size_t b = smp.imageStart[k], e = smp.imageStart[k + 1];
		std::fill(hist.begin(), hist.end(), 0.0);
		double total = 0;
		size_t used = 0;
		for (size_t i = b; i < e; i++)
		{
			const float sgn = smp.dl[i] < 0 ? 1.0f : -1.0f;
			const float dx = sgn * smp.dx[i], dy = sgn * smp.dy[i];
			const float c2 = dx * dx + dy * dy;
			if (c2 < kMinChromaStep * kMinChromaStep) continue;
			// Illumination edges are brightness edges first: a sun -> sky
			// shadow drops log-brightness by ~1-2 and moves the
			// log-chromaticity by ~0.5 (see header); steps that change colour
			// more than brightness are material edges.
			if (c2 > maxRatio2 * smp.dl[i] * smp.dl[i]) continue;
			const double ang = std::atan2(double(dy), double(dx));	 // (-pi, pi]
			const int bin = std::clamp(int((ang + M_PI) / (2 * M_PI) * kBins), 0, kBins - 1);
			const double w = std::abs(smp.dl[i]);
			hist[size_t(bin)] += w;
			total += w;
			used++;
		}
		if (used < kMinEdgeSamples) continue;
		std::vector<double> curve(out.alpha.size());
		for (size_t j = 0; j < out.alpha.size(); j++)
		{
			const double phi = std::atan2(out.alpha[j], 1.0);
			double d = 0;
			const int centre = int((phi + M_PI) / (2 * M_PI) * kBins);
			const int reach = int(4 * kBandwidth / (2 * M_PI) * kBins) + 1;
			for (int q = centre - reach; q <= centre + reach; q++)
			{
				const int qq = (q + kBins) % kBins;
				const double a = (qq + 0.5) * 2 * M_PI / kBins - M_PI - phi;
				d += hist[size_t(qq)] * std::exp((std::cos(a) - 1) / (kBandwidth * kBandwidth));
			}
			curve[j] = -d / total;
		}
		perImage.push_back(std::move(curve));
	}
	if (perImage.empty())
		throw std::invalid_argument(
			"alpha by edges: no image has " + std::to_string(kMinEdgeSamples) +
			" trusted coloured edge samples (flat, dark, grey or saturated images?)");
	out.items = int(perImage.size());
	bootstrapMeanCurve(perImage, s, out);
	return out;
}

// ---- 3. same view, different light ----------------------------------------------
TAlphaCurve alphaFromChromaChanges(
	const std::vector<TChromaChanges>& items, const TAlphaSearch& s, double minChromaChange, size_t minSamples,
	const std::string& method, std::vector<std::string>* skipped)
{
	s.validate();
	TAlphaCurve out;
	out.method = method;
	out.costName = "median change of the unit-norm invariant between the lights (geometric mean over items)";
	out.alpha = s.grid();
	const float minChange2 = float(minChromaChange * minChromaChange);
	std::vector<std::vector<double>> perItem;
	for (const auto& it : items)
	{
		// Points whose light did not change carry no information.
		std::vector<float> dx, dy;
		for (size_t i = 0; i < it.size(); i++)
		{
			const float ddx = it.xb[i] - it.xa[i], ddy = it.yb[i] - it.ya[i];
			if (ddx * ddx + ddy * ddy < minChange2) continue;
			dx.push_back(ddx), dy.push_back(ddy);
		}
		if (dx.size() < minSamples)
		{
			if (skipped)
				skipped->push_back(
					it.name + " (" + std::to_string(dx.size()) + " trusted points changed colour; need " +
					std::to_string(minSamples) + ")");
			continue;
		}
		// Distance of each change (dx, dy) from the line through the origin
		// along (1, alpha): |dy - alpha dx| / sqrt(1 + alpha^2), the change of
		// the unit-norm invariant. Its median over the points is a robust
		// line fit. Unlike a step relative to texture it is not biased
		// towards alphas that happen to show more texture, and isotropic
		// noise weighs the same at every alpha.
		std::vector<float> d(dx.size());
		std::vector<double> curve(out.alpha.size());
		for (size_t j = 0; j < out.alpha.size(); j++)
		{
			const float al = float(out.alpha[j]), norm = 1.0f / std::sqrt(1.0f + al * al);
			for (size_t i = 0; i < dx.size(); i++) d[i] = std::abs(dy[i] - al * dx[i]) * norm;
			curve[j] = std::log(std::max(1e-9, quantile(d, 0.5)));
		}
		perItem.push_back(std::move(curve));
	}
	if (perItem.empty())
		throw std::invalid_argument(
			"alpha from " + method + ": no item has enough trusted points whose colour changed between the two lights");
	out.items = int(perItem.size());
	bootstrapMeanCurve(perItem, s, out);
	for (auto& c : out.cost) c = std::exp(c);
	return out;
}

TAlphaCurve alphaFromSameView(
	const std::vector<TSameViewPair>& pairs, const TCalibrationInput& in, const TAlphaSearch& s,
	double minChromaChange, std::vector<std::string>* skipped)
{
	in.validate();
	const auto L = logTable(in);
	const auto ci = channelIndices(in.order);
	std::vector<TChromaChanges> items;
	for (const auto& p : pairs)
	{
		requireColour(p.a, "same-view pair '" + p.name + "' (first image)");
		requireColour(p.b, "same-view pair '" + p.name + "' (second image)");
		if (p.a.size() != p.b.size())
			throw std::invalid_argument("same-view pair '" + p.name + "': the two images differ in size");
		TChromaChanges it;
		it.name = p.name;
		const int top = int(in.skipTopFraction * p.a.rows);
		for (int y = top; y < p.a.rows; y += in.stride)
		{
			const uint8_t* ra = p.a.ptr<uint8_t>(y);
			const uint8_t* rb = p.b.ptr<uint8_t>(y);
			for (int x = 0; x < p.a.cols; x += in.stride)
			{
				const uint8_t* a = ra + 3 * x;
				const uint8_t* b = rb + 3 * x;
				if (!trusted(a, in) || !trusted(b, in)) continue;
				addChange(it, a, b, L, ci);
			}
		}
		items.push_back(std::move(it));
	}
	return alphaFromChromaChanges(items, s, minChromaChange, 500, "same-view", skipped);
}

// ---- 3b. two runs of one route ----------------------------------------------------
void TCrossRunMatching::validate() const
{
	if (features < 50) throw std::invalid_argument("cross-run matching: features must be >= 50");
	if (coarseFeatures < 50) throw std::invalid_argument("cross-run matching: coarseFeatures must be >= 50");
	if (candidates < 1) throw std::invalid_argument("cross-run matching: candidates must be >= 1");
	if (!(ratio > 0 && ratio <= 1)) throw std::invalid_argument("cross-run matching: ratio must be in (0, 1]");
	if (!(ransacPx > 0)) throw std::invalid_argument("cross-run matching: ransacPx must be > 0");
	if (minInliers < 8) throw std::invalid_argument("cross-run matching: minInliers must be >= 8");
	if (window < 0 || window > 10) throw std::invalid_argument("cross-run matching: window must be in [0, 10]");
	if (!(maxRoughness > 0)) throw std::invalid_argument("cross-run matching: maxRoughness must be > 0");
}

namespace
{
struct OrbFrame
{
	std::vector<cv::KeyPoint> kp;
	cv::Mat desc;
};

OrbFrame orbOf(const cv::Mat& grey, cv::ORB& orb)
{
	OrbFrame f;
	orb.detectAndCompute(grey, cv::noArray(), f.kp, f.desc);
	return f;
}

/** The monochrome image features are found on (the baseline channel's conversion). */
cv::Mat greyOf(const cv::Mat& colour, const TCalibrationInput& in, const std::string& what)
{
	requireColour(colour, what);
	cv::Mat grey;
	toMonochrome(colour, grey, in.order);
	return grey;
}

/** A's features matched in B that pass the ratio test. */
void ratioMatches(
	const OrbFrame& a, const OrbFrame& b, double ratio, std::vector<cv::Point2f>& pa, std::vector<cv::Point2f>& pb)
{
	pa.clear(), pb.clear();
	if (a.desc.rows < 2 || b.desc.rows < 2) return;
	cv::BFMatcher matcher(cv::NORM_HAMMING);
	std::vector<std::vector<cv::DMatch>> knn;
	matcher.knnMatch(a.desc, b.desc, knn, 2);
	for (const auto& k : knn)
		if (k.size() == 2 && k[0].distance < ratio * k[1].distance)
			pa.push_back(a.kp[size_t(k[0].queryIdx)].pt), pb.push_back(b.kp[size_t(k[0].trainIdx)].pt);
}

/** RANSAC inliers (point pairs) of A's features matched in B. */
std::vector<std::pair<cv::Point2f, cv::Point2f>> matchedInliers(
	const OrbFrame& a, const OrbFrame& b, const TCrossRunMatching& m)
{
	std::vector<std::pair<cv::Point2f, cv::Point2f>> out;
	std::vector<cv::Point2f> pa, pb;
	ratioMatches(a, b, m.ratio, pa, pb);
	if (int(pa.size()) < m.minInliers) return out;
	std::vector<uchar> mask;
	const cv::Mat F = cv::findFundamentalMat(pa, pb, cv::FM_RANSAC, m.ransacPx, 0.999, mask);
	if (F.empty()) return out;
	for (size_t i = 0; i < mask.size(); i++)
		if (mask[i]) out.emplace_back(pa[i], pb[i]);
	return out;
}

/** The largest log step to a 4-neighbour over the three channels at (x, y):
 * small where the colour is locally flat, so that a pixel of misregistration
 * between the two runs samples the same surface. */
float logRoughness(const cv::Mat& img, int x, int y, const std::array<float, 256>& L)
{
	const uint8_t* c = img.ptr<uint8_t>(y) + 3 * x;
	float r = 0;
	for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
	{
		const uint8_t* n = img.ptr<uint8_t>(y + dy) + 3 * (x + dx);
		for (int k = 0; k < 3; k++) r = std::max(r, std::abs(L[c[k]] - L[n[k]]));
	}
	return r;
}
}  // namespace

std::vector<TChromaChanges> correspondencesAcrossRuns(
	const std::vector<cv::Mat>& runA, const std::vector<cv::Mat>& runB, const TCalibrationInput& in,
	const TCrossRunMatching& m, const std::function<void(const std::string&)>& progress)
{
	in.validate();
	m.validate();
	if (runA.empty() || runB.empty()) throw std::invalid_argument("cross-run matching: a run has no frames");
	auto orb = cv::ORB::create(m.features), coarseOrb = cv::ORB::create(m.coarseFeatures);
	std::vector<OrbFrame> fb, cb;
	for (size_t j = 0; j < runB.size(); j++)
	{
		const cv::Mat grey = greyOf(runB[j], in, "second run, frame " + std::to_string(j));
		fb.push_back(orbOf(grey, *orb));
		cb.push_back(orbOf(grey, *coarseOrb));
	}
	const auto L = logTable(in);
	const auto ci = channelIndices(in.order);
	std::vector<TChromaChanges> items;
	for (size_t i = 0; i < runA.size(); i++)
	{
		const cv::Mat grey = greyOf(runA[i], in, "first run, frame " + std::to_string(i));
		const OrbFrame fa = orbOf(grey, *orb), ca = orbOf(grey, *coarseOrb);
		// Candidates by ratio-test matches alone: RANSAC on every frame of B
		// would cost most of the time, mostly on frames that share nothing.
		std::vector<std::pair<size_t, size_t>> ranked;	// (coarse matches, B frame)
		std::vector<cv::Point2f> pa, pb;
		for (size_t j = 0; j < cb.size(); j++)
		{
			ratioMatches(ca, cb[j], m.ratio, pa, pb);
			ranked.emplace_back(pa.size(), j);
		}
		const size_t keep = std::min(ranked.size(), size_t(m.candidates));
		std::partial_sort(ranked.begin(), ranked.begin() + long(keep), ranked.end(), std::greater<>());
		size_t best = 0;
		std::vector<std::pair<cv::Point2f, cv::Point2f>> bestInliers;
		for (size_t k = 0; k < keep; k++)
		{
			auto inl = matchedInliers(fa, fb[ranked[k].second], m);
			if (inl.size() > bestInliers.size()) bestInliers = std::move(inl), best = ranked[k].second;
		}
		const std::string name = "frame " + std::to_string(i) + " ~ " + std::to_string(best);
		if (int(bestInliers.size()) < m.minInliers)
		{
			if (progress)
				progress(
					"frame " + std::to_string(i) + ": no frame of the second run matches (best " +
					std::to_string(bestInliers.size()) + " inliers, need " + std::to_string(m.minInliers) + ")");
			continue;
		}
		TChromaChanges it;
		it.name = name;
		const int topA = int(in.skipTopFraction * runA[i].rows), topB = int(in.skipTopFraction * runB[best].rows);
		const cv::Mat &A = runA[i], &B = runB[best];
		const int w = m.window;
		cv::Mat taken(A.size(), CV_8U, cv::Scalar(0));	// windows of nearby inliers overlap: each pixel once
		for (const auto& [pa, pb] : bestInliers)
		{
			const int ax = int(std::lround(pa.x)), ay = int(std::lround(pa.y));
			const int bx = int(std::lround(pb.x)), by = int(std::lround(pb.y));
			// The window around the match, pixel for pixel (nearby frames:
			// scale and rotation barely differ over a few pixels), where
			// both images are locally flat.
			for (int dy = -w; dy <= w; dy++)
				for (int dx = -w; dx <= w; dx++)
				{
					const int xa = ax + dx, ya = ay + dy, xb = bx + dx, yb = by + dy;
					if (xa < 1 || ya < std::max(1, topA) || xa >= A.cols - 1 || ya >= A.rows - 1) continue;
					if (xb < 1 || yb < std::max(1, topB) || xb >= B.cols - 1 || yb >= B.rows - 1) continue;
					if (taken.at<uint8_t>(ya, xa)) continue;
					taken.at<uint8_t>(ya, xa) = 1;
					const uint8_t* a = A.ptr<uint8_t>(ya) + 3 * xa;
					const uint8_t* b = B.ptr<uint8_t>(yb) + 3 * xb;
					if (!trusted(a, in) || !trusted(b, in)) continue;
					if (logRoughness(A, xa, ya, L) > m.maxRoughness || logRoughness(B, xb, yb, L) > m.maxRoughness)
						continue;
					addChange(it, a, b, L, ci);
				}
		}
		if (progress)
			progress(
				name + ": " + std::to_string(bestInliers.size()) + " inliers, " + std::to_string(it.size()) +
				" trusted colour samples");
		items.push_back(std::move(it));
	}
	return items;
}

// ---- 4. mapping -------------------------------------------------------------------
namespace
{
std::vector<float> invariantValues(const std::vector<cv::Mat>& images, const InvariantParams& p, int stride)
{
	p.validate();
	if (stride < 1) throw std::invalid_argument("mapping: stride must be >= 1");
	std::array<float, 256> L{};
	for (int v = 0; v < 256; v++) L[v] = float(std::log(linearise(v, p.linearisation, p.gamma)));
	const auto ci = channelIndices(p.order);
	const float a = float(p.alpha), b = float(p.beta);
	std::vector<float> out;
	for (size_t k = 0; k < images.size(); k++)
	{
		requireColour(images[k], "mapping image " + std::to_string(k));
		for (int y = 0; y < images[k].rows; y += stride)
		{
			const uint8_t* row = images[k].ptr<uint8_t>(y);
			for (int x = 0; x < images[k].cols; x += stride)
			{
				const uint8_t* px = row + 3 * x;
				out.push_back(L[px[ci.g]] - a * L[px[ci.b]] - b * L[px[ci.r]]);
			}
		}
	}
	if (out.empty()) throw std::invalid_argument("mapping: no images");
	return out;
}
}  // namespace

TMappingStats mappingStats(const std::vector<cv::Mat>& images, const InvariantParams& p, int stride)
{
	auto v = invariantValues(images, p, stride);
	TMappingStats st;
	size_t lo = 0, hi = 0;
	for (auto& x : v)
	{
		x = float(p.toGrey(double(x)));
		// Rounded to the nearest level: below 0.5 is 0, from 254.5 on is 255.
		lo += x < 0.5f;
		hi += x >= 254.5f;
	}
	st.clipLow = double(lo) / double(v.size());
	st.clipHigh = double(hi) / double(v.size());
	st.p1 = quantile(v, 0.01);
	st.p99 = quantile(v, 0.99);
	return st;
}

InvariantParams calibrateMapping(
	const std::vector<cv::Mat>& images, InvariantParams p, double tailShare, int stride, double minSpan)
{
	if (!(tailShare > 0 && tailShare < 0.01)) throw std::invalid_argument("mapping: tail share must be in (0, 0.01)");
	if (!(minSpan >= 0 && minSpan <= 240)) throw std::invalid_argument("mapping: minimum span must be in [0, 240]");
	auto v = invariantValues(images, p, stride);
	const double lo = quantile(v, tailShare), hi = quantile(v, 1.0 - tailShare);
	const double p1 = quantile(v, 0.01), p99 = quantile(v, 0.99);
	if (!(hi > lo))
		throw std::invalid_argument("mapping: the invariant is constant over the calibration images (grey scene?)");
	p.knee_low = 0;
	p.knee_high = 255;
	p.tail_slope_low = p.tail_slope_high = 1;
	// Linear: the tail quantiles to 0.5 and 254.5 (they round to 0 and 255).
	p.scale = 254.0 / (hi - lo);
	p.offset = 0.5 / p.scale - lo;
	if (p.scale * (p99 - p1) < minSpan)
	{
		// Heavy tails: the 1st-99th percentiles get minSpan levels, and both
		// tails share the rest at one slope, in proportion to their lengths
		// in I. The slope is below 1 since minSpan exceeds the linear span.
		const double lenLow = p1 - lo, lenHigh = hi - p99;
		p.scale = minSpan / (p99 - p1);
		const double tailLevels = 254.0 - minSpan;
		const double slope = tailLevels / (p.scale * (lenLow + lenHigh));
		p.knee_low = 0.5 + slope * p.scale * lenLow;
		p.knee_high = p.knee_low + minSpan;
		p.offset = p.knee_low / p.scale - p1;
		p.tail_slope_low = p.tail_slope_high = std::min(1.0, slope);
	}
	p.validate();
	return p;
}

}  // namespace shadyloc::image
