/* Calibrating the invariant transform from data (docs/calibration.md):
 *  - synthetic scenes under an exact narrowband/Wien model, where the true
 *    alpha is known in closed form;
 *  - the simulator with several camera models against each camera's
 *    black-body reference alpha;
 *  - the real UIUC shadow pairs (Guo et al., CVPR 2011), skipped if absent;
 *  - the command line. */
#include "../support/TestSupport.h"

#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/image/InvariantCalibration.h>
#include <shadyloc/image/ShadowMetrics.h>
#include <shadyloc/sim/StereoSimulator.h>
#include <shadyloc/sim/Spectral.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <random>
#include <regex>

using namespace shadyloc::image;
namespace fs = std::filesystem;

namespace
{
// ---- synthetic scenes: narrowband sensors, Wien's approximation ------------
// log R_k = log I0 + log rho_k - 5 log l_k - c2 / (T l_k): with beta = 1 - alpha
// and alpha from the peak wavelengths, I does not depend on I0 or T at all.
constexpr double kC2 = 1.4388e7;  // nm K
const double kL[3] = {450.0, 545.0, 610.0};	 // blue, green, red peaks (nm)
double trueAlpha() { return InvariantParams::FromWavelengths(kL[0], kL[1], kL[2]).alpha; }

struct Light
{
	double T, I0;
};
// Linear response in [0,1] of channel k for reflectance rho under light: the
// light's I0 is its green response to white (a per-light scale, which the
// invariant cancels), white balanced at 6500 K (a per-channel constant).
double planckTerm(int k, double T) { return std::pow(kL[k], -5) * std::exp(-kC2 / (T * kL[k])); }
double wien(int k, double rho, const Light& l)
{
	const double wb = planckTerm(1, 6500) / planckTerm(k, 6500);
	return 0.7 * l.I0 * rho * wb * planckTerm(k, l.T) / planckTerm(1, l.T);
}

/** A scene of coloured cells with fine brightness texture (seeded); `inShadow`
 * marks pixels lit by `shadowLight` instead of `light`. Linear 8-bit, BGR. */
cv::Mat syntheticScene(
	uint32_t seed, const Light& light, const Light& shadowLight, const cv::Mat& inShadow, int w = 240, int h = 180)
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> u(0.08, 0.9);
	const int cell = 30;
	std::vector<std::array<double, 3>> rho((w / cell + 1) * (h / cell + 1));
	for (auto& r : rho) r = {u(rng), u(rng), u(rng)};
	cv::Mat tex(h, w, CV_64F);
	cv::RNG(seed).fill(tex, cv::RNG::UNIFORM, 0.85, 1.15);	// brightness texture (same for every light; own seed:
															// cv::randu would depend on the tests run before)
	cv::Mat img(h, w, CV_8UC3);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++)
		{
			const auto& r = rho[(y / cell) * (w / cell + 1) + x / cell];
			const Light& l = inShadow.empty() || !inShadow.at<uint8_t>(y, x) ? light : shadowLight;
			for (int k = 0; k < 3; k++)
				img.at<cv::Vec3b>(y, x)[k] = cv::saturate_cast<uint8_t>(255.0 * wien(k, r[k] * tex.at<double>(y, x), l));
		}
	return img;
}

cv::Mat shadowShape(int seed, int w = 240, int h = 180)
{
	cv::Mat m(h, w, CV_8U, cv::Scalar(0));
	std::mt19937 rng(seed);
	std::uniform_int_distribution<int> px(0, w - 1), py(0, h - 1);
	for (int i = 0; i < 3; i++) cv::circle(m, {px(rng), py(rng)}, 25 + i * 10, cv::Scalar(255), cv::FILLED);
	return m;
}

const Light kSun{5200, 1.0}, kSky{13000, 0.18};

TCalibrationInput linearInput()
{
	TCalibrationInput in;
	in.linearisation = Linearisation::None;
	return in;
}
TAlphaSearch quickSearch(int boot = 0)
{
	TAlphaSearch s;
	s.bootstrapRounds = boot;
	return s;
}
}  // namespace

// The pair method recovers the true alpha of an exact model. Tolerance 0.01:
// 8-bit linear quantisation of codes >= 8 perturbs each log by < 1/16, the
// medians over thousands of pixels shrink that far below 0.01 (a third of
// the goal of 0.03).
TEST(InvariantCalibration, PairsRecoverTrueAlphaOfExactModel)
{
	std::vector<TShadowPair> pairs;
	for (int i = 0; i < 4; i++)
	{
		const cv::Mat shape = shadowShape(10 + i);
		pairs.push_back(
			{"syn" + std::to_string(i), syntheticScene(i, kSun, kSun, {}), syntheticScene(i, kSun, kSky, shape)});
	}
	const auto c = alphaFromShadowPairs(pairs, linearInput(), quickSearch(50));
	std::printf("true alpha %.4f, pairs estimate %.4f [%.4f, %.4f]\n", trueAlpha(), c.best, c.ciLow, c.ciHigh);
	EXPECT_EQ(c.items, 4);
	EXPECT_NEAR(c.best, trueAlpha(), 0.01);
	EXPECT_LE(c.ciLow, c.best);
	EXPECT_GE(c.ciHigh, c.best);
	// The least-squares refinement makes the estimate independent of the grid.
	auto fine = quickSearch(), coarse = quickSearch();
	fine.step = 0.0025, coarse.step = 0.02;
	const double aFine = alphaFromShadowPairs(pairs, linearInput(), fine).best;
	const double aCoarse = alphaFromShadowPairs(pairs, linearInput(), coarse).best;
	std::printf("grid 0.0025: %.4f, grid 0.02: %.4f\n", aFine, aCoarse);
	EXPECT_NEAR(aFine, c.best, 0.003);
	EXPECT_NEAR(aCoarse, c.best, 0.003);
	// The curve has its minimum inside and rises away from it: a real optimum.
	const auto i = size_t(std::min_element(c.cost.begin(), c.cost.end()) - c.cost.begin());
	EXPECT_GT(c.cost.front(), 2 * c.cost[i]);
	EXPECT_GT(c.cost.back(), 2 * c.cost[i]);
}

TEST(InvariantCalibration, SameViewRecoversTrueAlphaOfExactModel)
{
	std::vector<TSameViewPair> pairs;
	for (int i = 0; i < 3; i++)
		pairs.push_back(
			{"syn" + std::to_string(i), syntheticScene(20 + i, {4000, 1.0}, {4000, 1.0}, {}),
			 syntheticScene(20 + i, {9000, 0.6}, {9000, 0.6}, {})});
	const auto c = alphaFromSameView(pairs, linearInput(), quickSearch(50));
	std::printf("true alpha %.4f, same-view estimate %.4f [%.4f, %.4f]\n", trueAlpha(), c.best, c.ciLow, c.ciHigh);
	EXPECT_NEAR(c.best, trueAlpha(), 0.01);	 // as above: quantisation only
}

// Unsupervised methods on single images with shadows (no pairing). Edges:
// tolerance 0.02, the kernel density's resolution (bandwidth 3.4 degrees is
// ~0.06 in alpha; its peak is found to a third of that on clean data).
TEST(InvariantCalibration, UnsupervisedMethodsRecoverTrueAlphaOfExactModel)
{
	std::vector<cv::Mat> imgs;
	for (int i = 0; i < 6; i++) imgs.push_back(syntheticScene(30 + i, kSun, kSky, shadowShape(40 + i)));
	const auto in = linearInput();
	const auto edges = alphaByEdgeDirections(edgeSamples(imgs, in), quickSearch());
	const auto entropy = alphaByEntropy(chromaSamples(imgs, in), quickSearch());
	std::printf(
		"true alpha %.4f, edges %.4f (%d images), entropy %.4f\n", trueAlpha(), edges.best, edges.items, entropy.best);
	EXPECT_EQ(edges.items, 6);
	EXPECT_NEAR(edges.best, trueAlpha(), 0.02);
	// Finlayson-Drew-Lu entropy works on such scenes (few flat colours, big shadows).
	EXPECT_NEAR(entropy.best, trueAlpha(), 0.03);
}

// The fast entropy (quantiles and bins from a fine histogram) follows the
// exact one (partial sorts). The histograms' grids start at a fine-bin edge
// instead of at the 5 % value, so where a clump of equal values falls
// (these noise-free scenes have few distinct 8-bit values) can change:
// measured curve differences 0.019 nats here, <= 0.005 on the simulator and
// 0.0075 on the UIUC images, with curves spanning 0.18-0.31 nats (bound 0.03).
// Both minima stay within 0.015 of the true alpha (half the goal).
TEST(InvariantCalibration, FastEntropyFollowsExactEntropy)
{
	std::vector<cv::Mat> imgs;
	for (int i = 0; i < 6; i++) imgs.push_back(syntheticScene(30 + i, kSun, kSky, shadowShape(40 + i)));
	const auto smp = chromaSamples(imgs, linearInput());
	auto s = quickSearch();
	s.step = 0.01;
	const auto fast = alphaByEntropy(smp, s, EntropyQuantiles::Histogram);
	const auto exact = alphaByEntropy(smp, s, EntropyQuantiles::Sorted);
	double maxDiff = 0;
	for (size_t j = 0; j < fast.cost.size(); j++) maxDiff = std::max(maxDiff, std::abs(fast.cost[j] - exact.cost[j]));
	std::printf("entropy: fast %.4f, exact %.4f, curves differ by <= %.4f nats\n", fast.best, exact.best, maxDiff);
	EXPECT_LT(maxDiff, 0.03);
	EXPECT_NEAR(fast.best, trueAlpha(), 0.015);
	EXPECT_NEAR(exact.best, trueAlpha(), 0.015);
}

// Saturated sky (clipped white) and black areas are left out: the estimate
// does not move when a third of every image is blown out or black.
TEST(InvariantCalibration, SaturatedAndDarkPixelsDoNotMoveTheEstimate)
{
	std::vector<cv::Mat> clean, spoiled;
	for (int i = 0; i < 6; i++)
	{
		clean.push_back(syntheticScene(30 + i, kSun, kSky, shadowShape(40 + i)));
		cv::Mat s = clean.back().clone();
		s(cv::Rect(0, 0, s.cols, s.rows / 4)).setTo(cv::Scalar(255, 252, 240));	 // blown-out sky, blue-white
		s(cv::Rect(0, s.rows - 20, s.cols, 20)).setTo(cv::Scalar(2, 3, 1));	 // black
		spoiled.push_back(s);
	}
	const auto in = linearInput();
	const auto a = alphaByEdgeDirections(edgeSamples(clean, in), quickSearch());
	const auto b = alphaByEdgeDirections(edgeSamples(spoiled, in), quickSearch());
	EXPECT_NEAR(a.best, b.best, 0.01);
	const auto samples = chromaSamples(spoiled, in);
	EXPECT_LT(samples.size(), chromaSamples(clean, in).size() * 0.8);  // they were really skipped
}

// The mapping: <= 0.5 % clipped on the calibration images by construction
// (0.2 % per tail), span of the 1st-99th percentiles reported.
TEST(InvariantCalibration, MappingClipsWithinTarget)
{
	std::vector<cv::Mat> imgs;
	for (int i = 0; i < 4; i++) imgs.push_back(syntheticScene(50 + i, kSun, kSky, shadowShape(60 + i)));
	auto p = linearInput().params(trueAlpha());
	p.scale = 2000;	 // far too steep: most pixels clip
	const auto before = mappingStats(imgs, p);
	const auto cal = calibrateMapping(imgs, p);
	const auto after = mappingStats(imgs, cal);
	std::printf(
		"clipped %.2f %% -> %.2f %%, span %.1f grey levels (scale %.1f, offset %.3f)\n", 100 * before.clipped(),
		100 * after.clipped(), after.span(), cal.scale, cal.offset);
	EXPECT_GT(before.clipped(), 0.2);
	EXPECT_LE(after.clipped(), 0.005);
	EXPECT_GT(after.span(), 150.0);
	EXPECT_EQ(cal.alpha, p.alpha);
}

// Heavy tails (a saturated red and a saturated blue object on 0.8 % of each
// image each, like the UIUC pairs' red cup, on a scene of muted colours):
// linear, the 1st-99th percentiles get few levels; the default compresses
// the tails so that they get the minimum span and clipping stays at the tail
// share. Light tails (the muted scene alone) stay linear.
TEST(InvariantCalibration, MappingCompressesHeavyTailsOnly)
{
	std::vector<cv::Mat> light, heavy;
	cv::RNG rng(5);
	for (int i = 0; i < 4; i++)
	{
		cv::Mat m(180, 240, CV_8UC3);
		for (int y = 0; y < m.rows; y++)
			for (int x = 0; x < m.cols; x++)
			{
				const double base = rng.uniform(40.0, 220.0);
				for (int k = 0; k < 3; k++)
					m.at<cv::Vec3b>(y, x)[k] = cv::saturate_cast<uint8_t>(base * rng.uniform(0.85, 1.15));
			}
		light.push_back(m);
		cv::Mat h = m.clone();
		// Graded saturation, so the tails are long rather than one spike.
		const int side = int(std::sqrt(0.008 * h.total()));
		for (int y = 0; y < side; y++)
			for (int x = 0; x < side; x++)
			{
				const int weak = 3 + 60 * (x + y) / (2 * side);
				h.at<cv::Vec3b>(10 + y, 10 + x) = cv::Vec3b(weak, weak + 5, 230);  // BGR: red
				h.at<cv::Vec3b>(h.rows - 10 - side + y, h.cols - 10 - side + x) = cv::Vec3b(230, weak + 10, weak);	// blue
			}
		heavy.push_back(h);
	}
	const auto p = linearInput().params(trueAlpha());
	const auto lightCal = calibrateMapping(light, p);
	EXPECT_FALSE(lightCal.hasCompressedTails());
	EXPECT_EQ(lightCal.scale, calibrateMapping(light, p, 0.002, 2, 0.0).scale);

	const auto linear = calibrateMapping(heavy, p, 0.002, 2, 0.0);
	const auto tone = calibrateMapping(heavy, p);
	const auto stLin = mappingStats(heavy, linear), stTone = mappingStats(heavy, tone);
	std::printf(
		"heavy tails: linear %.2f %% clipped, span %.1f; compressed %.2f %% clipped, span %.1f (knees %.1f / %.1f, "
		"slope %.3f)\n",
		100 * stLin.clipped(), stLin.span(), 100 * stTone.clipped(), stTone.span(), tone.knee_low, tone.knee_high,
		tone.tail_slope_low);
	ASSERT_LT(stLin.span(), 200.0);	 // the case this exists for
	EXPECT_TRUE(tone.hasCompressedTails());
	EXPECT_NEAR(stTone.span(), 210.0, 1.0);
	EXPECT_LE(stTone.clipped(), 0.005);
	EXPECT_LT(tone.tail_slope_low, 1.0);
	EXPECT_EQ(tone.knee_high - tone.knee_low, 210.0);
	// The 8-bit images carry it (fast path): the middle gets more levels.
	cv::Mat a, b;
	InvariantTransform(linear).apply(heavy[0], a);
	InvariantTransform(tone).apply(heavy[0], b);
	cv::Scalar ma, sa, mb, sb;
	cv::meanStdDev(a(cv::Rect(a.cols / 3, a.rows / 3, a.cols / 3, a.rows / 3)), ma, sa);
	cv::meanStdDev(b(cv::Rect(b.cols / 3, b.rows / 3, b.cols / 3, b.rows / 3)), mb, sb);
	EXPECT_GT(sb[0], 1.2 * sa[0]);
}

TEST(InvariantCalibration, BadInputNamesTheProblem)
{
	const cv::Mat grey(50, 50, CV_8U, cv::Scalar(100));
	try
	{
		chromaSamples({grey}, linearInput());
		FAIL() << "grey image accepted";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("calibration image 0"), std::string::npos) << e.what();
	}
	const cv::Mat flat(50, 50, CV_8UC3, cv::Scalar(100, 100, 100));
	TShadowPair same{"same", flat, flat};
	EXPECT_THROW(alphaFromShadowPairs({same}, linearInput(), quickSearch()), std::invalid_argument);
	TShadowPair sizes{"sizes", flat, cv::Mat(40, 50, CV_8UC3, cv::Scalar(1, 2, 3))};
	EXPECT_THROW(alphaFromShadowPairs({sizes}, linearInput(), quickSearch()), std::invalid_argument);
	TAlphaSearch bad;
	bad.alphaMin = 0.9, bad.alphaMax = 0.1;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
	auto in = linearInput();
	in.maxCode = 3;
	EXPECT_THROW(in.validate(), std::invalid_argument);
}

// ---- the simulator: several camera models ----------------------------------
namespace
{
struct CameraModel
{
	std::array<double, 3> peaks;
	double sigma;
	bool srgb;
	std::string name() const
	{
		char b[96];
		std::snprintf(b, sizeof b, "%.0f/%.0f/%.0f s%.0f %s", peaks[0], peaks[1], peaks[2], sigma, srgb ? "srgb" : "linear");
		return b;
	}
};

/** Linear float image (BGR) -> 8-bit through the given gain with the
 * simulator's noise model (shot + read noise), linear or sRGB-encoded. */
cv::Mat exposeCamera(const cv::Mat& lin, double gain, bool srgb, uint64_t seed)
{
	cv::RNG rng(seed);
	const double ePerLevel = 9000.0 / 255.0, rn = 10.0;
	cv::Mat out(lin.size(), CV_8UC3);
	for (int y = 0; y < lin.rows; y++)
	{
		const float* p = lin.ptr<float>(y);
		uint8_t* o = out.ptr<uint8_t>(y);
		for (int i = 0; i < 3 * lin.cols; i++)
		{
			double x = gain * p[i];
			x += rng.gaussian(std::sqrt(std::max(x, 0.0) * ePerLevel + rn * rn) / ePerLevel);
			double v = std::clamp(x / 255.0, 0.0, 1.0);
			if (srgb) v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
			o[i] = uint8_t(std::lround(255.0 * v));
		}
	}
	return out;
}

struct SimData
{
	std::vector<TShadowPair> pairs;
	std::vector<TSameViewPair> views;
	/** One view under two pure black bodies: overcast (skylight only) at
	 * 2 500, 5 000 and 20 000 K, the ends and middle of the reference's range. */
	std::vector<TSameViewPair> viewsBlackBody;
	std::vector<cv::Mat> images;
	double reference = 0, peakFormula = 0, referenceFlat = 0;
	/** The simulator's own lights instead of black bodies: the alpha
	 * minimising the variance of I over the sun + sky mixtures of noon (the
	 * shadow pairs' light) and of noon with morning / with evening (the
	 * same-view pairs' lights), from the spectra (sceneIlluminantAlpha()). */
	double illumPairs = 0, illumViews = 0;
	/** Each estimator's own criterion on the exact (float, before noise and
	 * 8 bits) log-chromaticities of the pixels it uses (ExactChroma): the
	 * direction of the scene's light changes as that method sees it. */
	double exactPairs = 0, exactViews = 0;
};

/** alpha (beta = 1 - alpha) minimising the variance of I, pooled over the
 * simulator's 20 material spectra, over the illuminants a point receives in
 * the given traversals: V max(0, n.s) E_sun + v E_sky (StereoSimulator::shade)
 * for direct-sun factors 0, 0.1, .., 1 and sky visibilities 0.5 (a wall) and
 * 1 (the road). Each group of traversals pools its lights (a same-view pair
 * sees two traversals); the groups' within-material covariances are summed.
 * Closed form as sim::blackBodyReferenceAlpha: sum cov(x, y) / sum var(x). */
double sceneIlluminantAlpha(
	shadyloc::sim::StereoSimulator& sim, const std::vector<std::vector<shadyloc::sim::TTraversal>>& groups)
{
	using namespace shadyloc::sim;
	double sumCov = 0, sumVar = 0;
	for (const auto& g : groups)
		for (int m = kAsphalt; m < kMarker; m++)
			for (float mix : {0.f, 1.f})
			{
				std::vector<double> xs, ys;
				for (const auto& t : g)
				{
					sim.setTraversal(t);
					for (int s = 0; s <= 10; s++)
						for (float v : {0.5f, 1.f})
						{
							const Rgb r = sim.shade(m, mix, 1.f, 0.1f * float(s), v);
							xs.push_back(std::log(r[0] / r[2]));
							ys.push_back(std::log(r[1] / r[2]));
						}
				}
				const double n = double(xs.size());
				const double mx = std::accumulate(xs.begin(), xs.end(), 0.0) / n;
				const double my = std::accumulate(ys.begin(), ys.end(), 0.0) / n;
				for (size_t i = 0; i < xs.size(); i++)
					sumCov += (xs[i] - mx) * (ys[i] - my), sumVar += (xs[i] - mx) * (xs[i] - mx);
			}
	return sumCov / sumVar;
}

/** Exact log-chromaticities (x, y) of the pixels an estimator uses, from
 * the float linear renders (BGR) before noise and 8 bits, one item per pair
 * of images; and the estimators' own criteria on them, so that the estimate
 * on the 8-bit noisy data can be told apart from the direction of the light
 * changes in the scene. */
struct ExactChroma
{
	struct Item
	{
		std::vector<float> xa, ya, xb, yb;
	};
	std::vector<Item> items;
	void add(const cv::Vec3f& a, const cv::Vec3f& b)
	{
		auto& it = items.back();
		it.xa.push_back(std::log(a[0] / a[2])), it.ya.push_back(std::log(a[1] / a[2]));
		it.xb.push_back(std::log(b[0] / b[2])), it.yb.push_back(std::log(b[1] / b[2]));
	}
	/** Argmin over alpha (grid 0.0025) of the sum over items of the log of
	 * the same-view criterion (relativeStep false: the median of
	 * |dy - alpha dx| / sqrt(1 + alpha^2)) or of the pair criterion (true:
	 * relativeShadowStepOfValues() on 255 I). */
	double fit(bool relativeStep) const
	{
		double best = 0, bestCost = 1e30;
		for (double al = 0.05; al <= 0.95; al += 0.0025)
		{
			double cost = 0;
			for (const auto& it : items)
			{
				if (it.xa.size() < 100) continue;
				std::vector<double> va(it.xa.size()), vb(it.xa.size());
				for (size_t i = 0; i < va.size(); i++)
					va[i] = 255 * (it.ya[i] - al * it.xa[i]), vb[i] = 255 * (it.yb[i] - al * it.xb[i]);
				if (relativeStep)
					cost += std::log(relativeShadowStepOfValues(va, vb).relative());
				else
				{
					for (size_t i = 0; i < va.size(); i++) va[i] = std::abs(vb[i] - va[i]);
					std::nth_element(va.begin(), va.begin() + long(va.size() / 2), va.end());
					cost += std::log(std::max(1e-9, va[va.size() / 2] / std::sqrt(1 + al * al)));
				}
			}
			if (cost < bestCost) bestCost = cost, best = al;
		}
		return best;
	}
};

SimData simulate(const CameraModel& cam)
{
	using namespace shadyloc::sim;
	auto opts = TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	opts.camera.width = 256;
	opts.camera.height = 192;
	opts.camera.spectral.peak_nm = cam.peaks;
	opts.camera.spectral.sigma_nm = cam.sigma;
	SimData d;
	const auto sens = opts.camera.spectral.sensitivities(opts.camera.grid);
	std::vector<Spectrum> refl;
	for (int m = kAsphalt; m < kMarker; m++)
		for (int j = 0; j < 2; j++) refl.push_back(materialReflectance(m, j).sample(opts.camera.grid));
	d.reference = blackBodyReferenceAlpha(sens, opts.camera.grid, refl);
	d.referenceFlat = blackBodyReferenceAlpha(sens, opts.camera.grid);
	d.peakFormula = InvariantParams::FromWavelengths(cam.peaks[0], cam.peaks[1], cam.peaks[2]).alpha;

	StereoSimulator sim(opts);
	const TTraversal noon = opts.traversal("noon");
	TTraversal noonTurned = noon;  // same light, sun from elsewhere: shadows move
	noonTurned.sun_azimuth_deg += 100;
	const TTraversal morning = opts.traversal("morning_low_sun"), evening = opts.traversal("evening_warm");
	d.illumPairs = sceneIlluminantAlpha(sim, {{noon}});
	d.illumViews = sceneIlluminantAlpha(sim, {{noon, morning}, {noon, evening}});
	TCalibrationInput in;
	in.linearisation = cam.srgb ? Linearisation::SRGB : Linearisation::None;
	ExactChroma exactPairs, exactViews;
	uint64_t seed = 1, bbSeed = 1000;	// apart, so that adding one set left the other's noise as it was
	for (int frame : {10, 60, 110, 160, 220, 280, 340, 400})
	{
		sim.setTraversal(noon);
		const auto pose = sim.T_world_left(frame);
		cv::Mat linNoon, linTurned, linMorning, linEvening, r;
		sim.renderLinear(pose, linNoon, r);
		const double gNoon = sim.exposureGain(linNoon);
		sim.setTraversal(noonTurned);
		sim.renderLinear(pose, linTurned, r);
		sim.setTraversal(morning);
		sim.renderLinear(pose, linMorning, r);
		const double gMorning = sim.exposureGain(linMorning);
		sim.setTraversal(evening);
		sim.renderLinear(pose, linEvening, r);
		const double gEvening = sim.exposureGain(linEvening);
		const cv::Mat a = exposeCamera(linNoon, gNoon, cam.srgb, seed++);
		const cv::Mat b = exposeCamera(linTurned, gNoon, cam.srgb, seed++);	 // same exposure: a shadow pair
		const cv::Mat m = exposeCamera(linMorning, gMorning, cam.srgb, seed++);
		const cv::Mat e = exposeCamera(linEvening, gEvening, cam.srgb, seed++);
		const std::string f = std::to_string(frame);
		d.pairs.push_back({f + "a", a, b});
		d.pairs.push_back({f + "b", b, a});
		d.views.push_back({f + "m", a, m});
		d.views.push_back({f + "e", a, e});
		for (const auto* img : {&a, &m, &e}) d.images.push_back(*img);
		if (frame == 10 || frame == 110 || frame == 220 || frame == 340)	 // avenue to open stretch; half suffices
		{
			TTraversal sky = opts.traversal("overcast");
			std::vector<cv::Mat> shots;
			for (double kelvin : {2500.0, 5000.0, 20000.0})
			{
				sky.sky_temperature_K = kelvin;
				sim.setTraversal(sky);
				cv::Mat lin;
				sim.renderLinear(pose, lin, r);
				shots.push_back(exposeCamera(lin, sim.exposureGain(lin), cam.srgb, bbSeed++));
			}
			d.viewsBlackBody.push_back({f + "bb1", shots[0], shots[1]});
			d.viewsBlackBody.push_back({f + "bb2", shots[1], shots[2]});
		}
		// The exact changes at the pixels the estimators use: the pair's
		// shadow mask; for same view, pixels trusted in both 8-bit images
		// whose exact chromaticity moved by more than 0.03 (every 2nd pixel).
		for (int k : {2, 1})
		{
			const auto& pair = d.pairs[d.pairs.size() - size_t(k)];
			const cv::Mat mask = shadowMask(pair, in);
			if (cv::countNonZero(mask) < std::max(100.0, 0.01 * double(mask.total()))) continue;	// as the estimator
			const cv::Mat& linFree = k == 2 ? linNoon : linTurned;
			const cv::Mat& linShadow = k == 2 ? linTurned : linNoon;
			exactPairs.items.emplace_back();
			for (int y = 0; y < mask.rows; y++)
				for (int x = 0; x < mask.cols; x++)
					if (mask.at<uint8_t>(y, x)) exactPairs.add(linFree.at<cv::Vec3f>(y, x), linShadow.at<cv::Vec3f>(y, x));
		}
		const auto trustedPx = [&](const cv::Mat& img, int y, int x) {
			const auto v = img.at<cv::Vec3b>(y, x);
			return std::all_of(v.val, v.val + 3, [&](uint8_t c) { return c >= in.minCode && c < in.maxCode; });
		};
		for (const auto& [other8, otherLin] : {std::pair{&m, &linMorning}, std::pair{&e, &linEvening}})
		{
			exactViews.items.emplace_back();
			auto& it = exactViews.items.back();
			for (int y = 0; y < a.rows; y += 2)
				for (int x = 0; x < a.cols; x += 2)
				{
					if (!trustedPx(a, y, x) || !trustedPx(*other8, y, x)) continue;
					exactViews.add(linNoon.at<cv::Vec3f>(y, x), otherLin->at<cv::Vec3f>(y, x));
					const float ddx = it.xb.back() - it.xa.back(), ddy = it.yb.back() - it.ya.back();
					if (ddx * ddx + ddy * ddy < 0.03f * 0.03f)
						it.xa.pop_back(), it.ya.pop_back(), it.xb.pop_back(), it.yb.pop_back();
				}
		}
	}
	d.exactPairs = exactPairs.fit(true);
	d.exactViews = exactViews.fit(false);
	return d;
}
}  // namespace

// Must-show 1 and 4 (simulator part). Printed table = docs/calibration.md.
// Why a lower alpha localises better on the simulator (docs/calibration.md,
// must-show 3): with the mapping calibrated per alpha, the invariant image's
// fine texture over its noise falls as alpha rises. Two exposures of each
// frame with different noise seeds separate the two (high-pass of a 2 px
// Gaussian; noise from the difference, texture from the mean). In log units
// the noise hardly changes with alpha; the texture that survives the
// projection does.
TEST(InvariantCalibrationSim, InvariantTextureOverNoiseFallsWithAlpha)
{
	using namespace shadyloc::sim;
	const auto opts = TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	StereoSimulator sim(opts);
	std::vector<std::pair<cv::Mat, cv::Mat>> shots;	 // the same frame, two noise seeds
	std::vector<cv::Mat> first;
	uint64_t seed = 100;
	for (const char* trav : {"noon", "morning_low_sun", "evening_warm", "overcast"})
	{
		sim.setTraversal(opts.traversal(trav));
		for (int frame = 10; frame <= 400; frame += 55)
		{
			cv::Mat lin, right, a, b;
			sim.renderLinear(sim.T_world_left(frame), lin, right);
			const double gain = sim.exposureGain(lin);
			sim.expose(lin, gain, seed++, a);
			sim.expose(lin, gain, seed++, b);
			shots.emplace_back(a, b);
			first.push_back(a);
		}
	}
	const auto highPass = [](const cv::Mat& m8) {
		cv::Mat f, blur;
		m8.convertTo(f, CV_32F);
		cv::GaussianBlur(f, blur, cv::Size(0, 0), 2.0);
		return cv::Mat(f - blur);
	};
	const auto variance = [](const cv::Mat& m) {
		cv::Scalar mu, sd;
		cv::meanStdDev(m, mu, sd);
		return sd[0] * sd[0];
	};
	std::vector<double> snr, texture, noise;  // texture and noise in log units
	for (double alpha : {0.2642, 0.3642, 0.4642, 0.5642})
	{
		const auto p = calibrateMapping(first, InvariantParams::FromAlphaBeta(alpha, 1 - alpha), 0.002, 2, 0.0);
		const InvariantTransform t(p);
		double tex2 = 0, noise2 = 0;
		for (const auto& [a, b] : shots)
		{
			cv::Mat ia, ib;
			t.apply(a, ia);
			t.apply(b, ib);
			const cv::Mat ha = highPass(ia), hb = highPass(ib);
			const double n2 = variance(ha - hb) / 2;  // one shot's noise
			tex2 += variance((ha + hb) * 0.5) - n2 / 2, noise2 += n2;
		}
		tex2 /= double(shots.size()), noise2 /= double(shots.size());
		snr.push_back(std::sqrt(tex2 / noise2));
		texture.push_back(std::sqrt(tex2) / p.scale);
		noise.push_back(std::sqrt(noise2) / p.scale);
		std::printf(
			"alpha %.4f: scale %.1f, high-pass texture %.4f, noise %.4f (log units), texture/noise %.3f\n", alpha,
			p.scale, texture.back(), noise.back(), snr.back());
	}
	double monoTex2 = 0, monoNoise2 = 0;  // the baseline channel, for scale
	for (const auto& [a, b] : shots)
	{
		cv::Mat ga, gb;
		toMonochrome(a, ga, ChannelOrder::BGR);
		toMonochrome(b, gb, ChannelOrder::BGR);
		const cv::Mat ha = highPass(ga), hb = highPass(gb);
		const double n2 = variance(ha - hb) / 2;
		monoTex2 += variance((ha + hb) * 0.5) - n2 / 2, monoNoise2 += n2;
	}
	const double monoSnr = std::sqrt(monoTex2 / monoNoise2);
	std::printf("monochrome: texture/noise %.2f\n", monoSnr);
	for (size_t i = 1; i < snr.size(); i++) EXPECT_LT(snr[i], snr[i - 1]) << "alpha step " << i;
	EXPECT_GT(monoSnr, 5 * snr[2]);	 // the invariant's detail is near its noise; mono's is not
	// The texture falls by a quarter or more from 0.26 to 0.56 (measured 32 %),
	// the noise by less than a tenth either way (measured 3 %).
	EXPECT_LT(texture.back(), 0.75 * texture.front());
	EXPECT_NEAR(noise.back() / noise.front(), 1.0, 0.1);
}

// Two runs of one route under different light (noon, morning), no poses:
// frames of the first are matched to frames of the second by features, and
// the pixels around the matches give the same-view data. Its estimate is
// compared with the same-view estimate on pixel-aligned renders of the first
// run's poses under the second run's light (the same lights, exact
// correspondences).
TEST(InvariantCalibrationSim, TwoRunsWithoutPosesAgreeWithAlignedSameView)
{
	using namespace shadyloc::sim;
	const auto opts = TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	StereoSimulator sim(opts);
	const TTraversal noon = opts.traversal("noon"), morning = opts.traversal("morning_low_sun");
	uint64_t seed = 500;
	const auto shoot = [&](const TTraversal& t, const mrpt::poses::CPose3D& pose) {
		sim.setTraversal(t);
		cv::Mat lin, right, out;
		sim.renderLinear(pose, lin, right);
		sim.expose(lin, sim.exposureGain(lin), seed++, out);
		return out;
	};
	std::vector<cv::Mat> runA, runB;
	std::vector<TSameViewPair> aligned;
	for (int frame = 20; frame <= 380; frame += 30)
	{
		sim.setTraversal(noon);
		const auto pose = sim.T_world_left(frame);
		runA.push_back(shoot(noon, pose));
		aligned.push_back({std::to_string(frame), runA.back(), shoot(morning, pose)});
	}
	for (int frame = 5; frame <= 395; frame += 6)  // the second run: its own poses
	{
		sim.setTraversal(morning);
		runB.push_back(shoot(morning, sim.T_world_left(frame)));
	}
	TCalibrationInput in;  // the simulator's camera is linear
	auto s = quickSearch();
	s.step = 0.01;
	s.bootstrapRounds = 100;
	size_t lines = 0;
	const auto items = correspondencesAcrossRuns(runA, runB, in, {}, [&](const std::string& l) {
		std::printf("  %s\n", l.c_str());
		lines++;
	});
	EXPECT_EQ(lines, runA.size());	// one progress line per frame of the first run
	const auto runs = alphaFromChromaChanges(items, s, 0.03, 50, "runs");
	const auto same = alphaFromSameView(aligned, in, s);
	std::printf(
		"two runs: alpha %.4f [%.4f, %.4f] from %d of %zu frames; aligned same view %.4f [%.4f, %.4f]\n", runs.best,
		runs.ciLow, runs.ciHigh, runs.items, runA.size(), same.best, same.ciLow, same.ciHigh);
	EXPECT_GE(runs.items, int(runA.size()) * 2 / 3);  // most frames find their place in the other run
	EXPECT_EQ(runs.method, "runs");
	// Matched pixels are noisier than aligned ones (misregistration, other
	// viewpoints): within 0.05 of the aligned estimate, and the aligned one
	// inside the interval.
	EXPECT_NEAR(runs.best, same.best, 0.05);
	EXPECT_LE(runs.ciLow, same.best);
	EXPECT_GE(runs.ciHigh, same.best);
}

TEST(InvariantCalibrationSim, EstimatesAgainstBlackBodyReference)
{
	const std::vector<CameraModel> cams{
		{{470, 540, 620}, 30, false}, {{450, 520, 600}, 20, true},	{{490, 560, 640}, 40, false},
		{{450, 560, 620}, 10, true},  {{490, 540, 600}, 25, true},	{{470, 520, 640}, 40, true},
	};
	std::printf(
		"%-24s %7s %7s %7s | %7s %7s %7s %7s | %7s %7s %7s %7s | %7s %7s %7s | %6s %6s %6s %6s\n", "camera", "ref",
		"refFlat", "peak", "illumP", "exactP", "pairs", "pairsG", "illumV", "exactV", "sameV", "sameBB", "edges", "edgesA",
		"entropy", "clipD%", "clipC%", "span", "spanL");
	std::vector<double> errPairs, errPairsGeo, errView, errEdges, errEdgesAll, errEntropy, errPairsExact, errViewExact,
		errViewIllum, errViewBlackBody;
	for (const auto& cam : cams)
	{
		const auto d = simulate(cam);
		TCalibrationInput in;
		in.linearisation = cam.srgb ? Linearisation::SRGB : Linearisation::None;
		auto s = quickSearch();
		s.step = 0.01;	// halves the time; the parabola refines below the grid
		const auto pairs = alphaFromShadowPairs(d.pairs, in, s);
		const auto pairsGeo = alphaFromShadowPairs(d.pairs, in, s, 0.01, nullptr, PairAverage::Geometric);
		const auto views = alphaFromSameView(d.views, in, s);
		const auto viewsBB = alphaFromSameView(d.viewsBlackBody, in, s);
		const auto edgeSmp = edgeSamples(d.images, in);
		const auto edges = alphaByEdgeDirections(edgeSmp, s);
		const auto edgesAll = alphaByEdgeDirections(edgeSmp, s, 1e6);	 // no bound: every coloured edge
		const auto entropy = alphaByEntropy(chromaSamples(d.images, in), s);
		auto pDef = in.params(d.reference);
		const auto clipDef = mappingStats(d.images, pDef);
		const auto cal = calibrateMapping(d.images, in.params(d.reference));
		const auto clipCal = mappingStats(d.images, cal);
		const auto clipLinear = mappingStats(d.images, calibrateMapping(d.images, in.params(d.reference), 0.002, 2, 0));
		std::printf(
			"%-24s %7.4f %7.4f %7.4f | %7.4f %7.4f %7.4f %7.4f | %7.4f %7.4f %7.4f %7.4f | %7.4f %7.4f %7.4f | %6.2f "
			"%6.2f %6.1f %6.1f\n",
			cam.name().c_str(), d.reference, d.referenceFlat, d.peakFormula, d.illumPairs, d.exactPairs, pairs.best,
			pairsGeo.best, d.illumViews, d.exactViews, views.best, viewsBB.best, edges.best, edgesAll.best, entropy.best,
			100 * clipDef.clipped(), 100 * clipCal.clipped(), clipCal.span(), clipLinear.span());
		errPairs.push_back(std::abs(pairs.best - d.reference));
		errPairsGeo.push_back(std::abs(pairsGeo.best - d.reference));
		errView.push_back(std::abs(views.best - d.reference));
		errEdges.push_back(std::abs(edges.best - d.reference));
		errEdgesAll.push_back(std::abs(edgesAll.best - d.reference));
		errEntropy.push_back(std::abs(entropy.best - d.reference));
		errPairsExact.push_back(std::abs(pairs.best - d.exactPairs));
		errViewExact.push_back(std::abs(views.best - d.exactViews));
		errViewIllum.push_back(std::abs(views.best - d.illumViews));
		errViewBlackBody.push_back(std::abs(viewsBB.best - d.reference));
		EXPECT_LE(clipCal.clipped(), 0.005) << cam.name();
		EXPECT_GE(clipCal.span(), 200.0) << cam.name();	 // the goal (the mapping aims at 210)
	}
	auto worst = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
	auto within = [](const std::vector<double>& v, double tol) {
		return int(std::count_if(v.begin(), v.end(), [&](double e) { return e <= tol; }));
	};
	std::printf(
		"worst |estimate - black-body reference|: pairs %.4f (geometric mean %.4f), same-view %.4f, edges %.4f "
		"(unbounded %.4f), entropy %.4f\n"
		"within 0.03 of it: pairs %d (geometric %d), same-view %d, edges %d (unbounded %d), entropy %d of %zu\n"
		"worst |estimate - the data's exact direction|: pairs %.4f, same-view %.4f; "
		"|same-view - the scene lights' reference| %.4f; same-view under black bodies: worst %.4f, within 0.03 %d\n",
		worst(errPairs), worst(errPairsGeo), worst(errView), worst(errEdges), worst(errEdgesAll), worst(errEntropy),
		within(errPairs, 0.03), within(errPairsGeo, 0.03), within(errView, 0.03), within(errEdges, 0.03),
		within(errEdgesAll, 0.03), within(errEntropy, 0.03), cams.size(), worst(errPairsExact), worst(errViewExact),
		worst(errViewIllum), worst(errViewBlackBody), within(errViewBlackBody, 0.03));
	// The goal is 0.03 from the black-body reference. The same-view
	// estimate sits 0.035-0.047 above it on every camera, and the cause is
	// physical (docs/calibration.md): the simulator's lights are sun + sky
	// mixtures, and the reference computed from those spectra instead of
	// black bodies (illumViews) is met within 0.016 (bound 0.025); its own
	// criterion on the noise-free renders (exactViews) within 0.026 (bound
	// 0.035). The pair criterion on noise-free renders (exactPairs) lies
	// -0.065..+0.025 from the black-body reference (dappled shadows: sun
	// fractions between 0 and 1, mixtures again); on the noisy 8-bit pairs the
	// estimate falls 0.006-0.057 below it (bound 0.065): few small shadow
	// masks and a shallow curve. These bounds guard the measured figures; the
	// unsupervised methods miss on the simulator (printed, not asserted).
	// Under pure black bodies (overcast at 2 500 / 5 000 / 20 000 K) the same
	// estimator meets the goal on every camera: worst 0.0095 (bound 0.02).
	EXPECT_LE(worst(errViewBlackBody), 0.02);
	EXPECT_LE(worst(errViewIllum), 0.025);
	EXPECT_LE(worst(errViewExact), 0.035);
	EXPECT_LE(worst(errView), 0.05);
	// Pairs (arithmetic mean over pairs, the default): within 0.03 of the
	// black-body reference on 5 of the 6 cameras (the geometric mean: 3). The
	// sixth, 490/560/640 s40, is the scene: its shadow pixels' own direction
	// on the noise-free renders (exactPairs) is 0.065 below the reference, and
	// every estimate is within 0.022 of that direction (bound 0.03, the goal:
	// noise and 8 bits cost the rest).
	EXPECT_GE(within(errPairs, 0.03), 5);
	EXPECT_LE(worst(errPairsExact), 0.03);
	EXPECT_LE(worst(errPairs), 0.075);
	// Edges: the bound on chromaticity per brightness step removes the
	// material edges that pulled the unbounded criterion 0.07-0.35 high; the
	// bounded one is within 0.056 on every camera (bound 0.07) and within
	// 0.03 on 3 of 6 (asserted: at least 2, one lies at 0.0298).
	EXPECT_LE(worst(errEdges), 0.07);
	EXPECT_LT(worst(errEdges), 0.3 * worst(errEdgesAll));
	EXPECT_GE(within(errEdges, 0.03), 2);
}

// ---- real shadow pairs (must-show 2 and 4) ------------------------------------
namespace
{
std::vector<TShadowPair> realPairs()
{
	const auto dir = shadyloc::test::sharedDataDir() + "/shadow-pairs";
	std::vector<TShadowPair> pairs;
	const std::regex re("(p\\d+)_shadow(\\d)\\.jpg");
	std::vector<std::string> names;
	for (auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
	std::sort(names.begin(), names.end());
	for (const auto& f : names)
	{
		std::smatch m;
		if (std::regex_match(f, m, re))
			pairs.push_back({m[1].str() + "_s" + m[2].str(), cv::imread(dir + "/" + m[1].str() + "_free.jpg"),
							 cv::imread(dir + "/" + f)});
	}
	return pairs;
}
}  // namespace

TEST(InvariantCalibrationReal, ShadowPairsAndUnsupervisedAgree)
{
	SHADYLOC_REQUIRE_SHARED_DATA("shadow-pairs");
	const auto pairs = realPairs();
	ASSERT_GE(pairs.size(), 20u);
	TCalibrationInput in;
	in.linearisation = Linearisation::SRGB;	 // JPEG
	TAlphaSearch s;
	s.bootstrapRounds = 100;
	s.step = 0.01;	// halves the time; the parabola refines below the grid
	const auto fromPairs = alphaFromShadowPairs(pairs, in, s);
	const auto fromPairsGeo = alphaFromShadowPairs(pairs, in, s, 0.01, nullptr, PairAverage::Geometric);
	std::vector<cv::Mat> imgs;
	for (const auto& p : pairs) imgs.push_back(p.free), imgs.push_back(p.shadow);
	const auto edgeSmp = edgeSamples(imgs, in);
	const auto edges = alphaByEdgeDirections(edgeSmp, s);
	const auto edgesAll = alphaByEdgeDirections(edgeSmp, s, 1e6);
	const auto entropy = alphaByEntropy(chromaSamples(imgs, in), quickSearch());
	std::printf(
		"pairs %.4f [%.4f, %.4f] (%d pairs; geometric mean %.4f [%.4f, %.4f]); edges %.4f [%.4f, %.4f] (unbounded "
		"%.4f [%.4f, %.4f]); entropy (FDL) %.4f\n",
		fromPairs.best, fromPairs.ciLow, fromPairs.ciHigh, fromPairs.items, fromPairsGeo.best, fromPairsGeo.ciLow,
		fromPairsGeo.ciHigh, edges.best, edges.ciLow, edges.ciHigh, edgesAll.best, edgesAll.ciLow, edgesAll.ciHigh,
		entropy.best);
	EXPECT_GE(fromPairs.items, 30);
	// The goal: the unsupervised estimate within 0.05 of the pair-based one.
	EXPECT_NEAR(edges.best, fromPairs.best, 0.05);
	// The arithmetic mean's estimate is at least as tight as the geometric
	// mean's (interval 0.067 wide against 0.099).
	EXPECT_LE(fromPairs.ciHigh - fromPairs.ciLow, fromPairsGeo.ciHigh - fromPairsGeo.ciLow);

	// Shadow step ratio (invariant / mono), median over pairs, at the
	// estimate vs the paper's default; both with a calibrated linear mapping
	// (minimum span 0), so that only alpha differs. The median of 8-bit
	// values is not scale-free where a mask's texture spread is at the
	// one-level floor (14 of these 40 pairs), so the steeper mapping with
	// compressed tails is compared on its own below.
	auto ratioAt = [&](const InvariantParams& p) {
		const InvariantTransform inv(p);
		std::vector<double> r;
		for (const auto& pr : pairs)
		{
			const cv::Mat mask = shadowMaskFromPair(pr.free, pr.shadow);
			if (cv::countNonZero(mask) < 0.01 * mask.total()) continue;
			cv::Mat mf, ms, i_f, i_s;
			toMonochrome(pr.free, mf, ChannelOrder::BGR);
			toMonochrome(pr.shadow, ms, ChannelOrder::BGR);
			inv.apply(pr.free, i_f);
			inv.apply(pr.shadow, i_s);
			r.push_back(relativeShadowStep(i_f, i_s, mask).relative() / relativeShadowStep(mf, ms, mask).relative());
		}
		std::nth_element(r.begin(), r.begin() + long(r.size() / 2), r.end());
		return r[r.size() / 2];
	};
	auto paper = InvariantParams::FromAlphaBeta(0.4800, 0.5065);
	paper.linearisation = Linearisation::SRGB;
	const auto linearAt = [&](double alpha) { return calibrateMapping(imgs, in.params(alpha), 0.002, 2, 0.0); };
	const auto linear = linearAt(fromPairs.best);
	const auto calibrated = calibrateMapping(imgs, in.params(fromPairs.best));	// default: compressed tails if needed
	const double rCal = ratioAt(linear), rDefault = ratioAt(paper);
	const double rGeo = ratioAt(linearAt(fromPairsGeo.best));
	const double rEdges = ratioAt(linearAt(edges.best));
	const auto clipPaper = mappingStats(imgs, paper), clipLinear = mappingStats(imgs, linear),
			   clipCal = mappingStats(imgs, calibrated);
	std::printf(
		"median shadow-step ratio invariant/mono: %.3f at the estimate (linear calibrated mapping; %.3f at the "
		"geometric-mean estimate, %.3f at the edges estimate), %.3f at the paper's alpha/beta and mapping, %.3f at the "
		"estimate with compressed tails\nclipping: %.2f %% (span %.1f) calibrated, %.2f %% (span %.1f) linear "
		"calibrated, %.2f %% (span %.1f) default; scale %.2f offset %.4f knees %.2f / %.2f tail slope %.4f\n",
		rCal, rGeo, rEdges, rDefault, ratioAt(calibrated), 100 * clipCal.clipped(), clipCal.span(),
		100 * clipLinear.clipped(), clipLinear.span(), 100 * clipPaper.clipped(), clipPaper.span(), calibrated.scale,
		calibrated.offset, calibrated.knee_low, calibrated.knee_high, calibrated.tail_slope_low);
	// The mapping goals: under 0.5 % clipped and a 1st-99th percentile
	// span of at least 200 levels. A linear mapping reaches only 144 here (heavy
	// red tails), so the tails are compressed; the span is 210 by construction
	// (1 level of slack: quantiles of a sample).
	EXPECT_LE(clipCal.clipped(), 0.005);
	EXPECT_GE(clipCal.span(), 209.0);
	EXPECT_TRUE(calibrated.hasCompressedTails());
	EXPECT_LT(clipLinear.span(), 200.0);
	EXPECT_LT(clipCal.clipped(), clipPaper.clipped());
	// The estimate is at least as good as the default on the metric it optimises
	// (10 % slack: the estimate optimises the geometric mean in float, this is the
	// median of the 8-bit channel).
	EXPECT_LT(rCal, 1.1 * rDefault);
	// Adopting the arithmetic mean did not make the real shadows worse:
	// 0.207 against 0.213 at the geometric mean's estimate. Slack 0.01: this
	// median over 40 pairs moves by up to 0.008 between alphas 0.003 apart
	// (the edges estimate 0.483 gives 0.215).
	EXPECT_LE(rCal, rGeo + 0.01);
}

// ---- the command --------------------------------------------------------------
namespace
{
/** The invariant filter of a filters .ini made of calibrate-alpha's OUT.ini
 * pasted under a one-filter [filters] pipeline (null if it is not one). */
std::shared_ptr<shadyloc::CFilterInvariant> filterFromCalibration(const std::string& iniPath)
{
	const std::string filtersIni = iniPath + ".filters.ini";
	{
		std::ifstream f(iniPath);
		std::ofstream g(filtersIni);
		g << "[filters]\npipeline = invariant\n" << f.rdbuf();
	}
	const auto pipe = shadyloc::filters::FilterPipeline::FromConfigFile(filtersIni);
	if (pipe.filters.size() != 1) return nullptr;
	return std::dynamic_pointer_cast<shadyloc::CFilterInvariant>(pipe.filters[0]);
}
}  // namespace

TEST(InvariantCalibrationApp, WritesIniCurveAndPlotThatLoadBack)
{
	const auto dir = shadyloc::test::tempDir("calib_app");
	std::string args;
	for (int i = 0; i < 3; i++)
	{
		const cv::Mat shape = shadowShape(70 + i);
		const std::string f = dir + "/s" + std::to_string(i) + "_free.png", s = dir + "/s" + std::to_string(i) + "_shadow1.png";
		cv::imwrite(f, syntheticScene(70 + i, kSun, kSun, {}));
		cv::imwrite(s, syntheticScene(70 + i, kSun, kSky, shape));
	}
	const bool havePlot = shadyloc::test::runCommand("command -v gnuplot >/dev/null") == 0;
	std::string out;
	// The outputs go beside the --pairs folder: inside it they are refused.
	const std::string images = dir;
	const auto dirOut = shadyloc::test::tempDir("calib_app_out");
	const int rc = shadyloc::test::runCommand(
		shadyloc::test::appPath() + " calibrate-alpha --pairs " + images + " --linearise none --bootstrap 20 " +
			(havePlot ? "" : "--no-plot ") + "-o " + dirOut + "/cam",
		&out);
	ASSERT_EQ(rc, 0) << out;
	EXPECT_NE(out.find("[invariant]"), std::string::npos) << out;
	ASSERT_TRUE(fs::exists(dirOut + "/cam.ini"));
	ASSERT_TRUE(fs::exists(dirOut + "/cam_curve.csv"));
	if (havePlot)
	{
		const cv::Mat png = cv::imread(dirOut + "/cam_curve.png");
		ASSERT_FALSE(png.empty());
		EXPECT_GE(png.cols, 600);
	}
	for (const auto& e : fs::directory_iterator(dirOut))
		EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "left over: " << e.path();
	// The section pastes into a filters .ini and loads back with the estimate.
	const auto inv = filterFromCalibration(dirOut + "/cam.ini");
	ASSERT_TRUE(inv);
	// 0.02: three small pairs, shadowed pixels at codes 8-40 (quantisation steps of 2.5-12 %).
	EXPECT_NEAR(inv->params().alpha, trueAlpha(), 0.02);
	EXPECT_NEAR(inv->params().alpha + inv->params().beta, 1.0, 1e-9);
	EXPECT_NE(inv->params().scale, 255.0);	// the mapping was calibrated

	// Bad input: clear message, non-zero exit, no output.
	const auto bad = shadyloc::test::tempDir("calib_app_bad");
	const auto badOut = shadyloc::test::tempDir("calib_app_bad_out");
	for (const auto& [args, expect] : std::vector<std::pair<std::string, std::string>>{
			 {"--pairs " + bad, "no <name>_free"},
			 {"--image " + bad + "/missing.png", "missing.png"},
			 {"--runs " + bad + "/a.rawlog", "--runs: expected two paths"},
			 {"--runs " + bad + "/a.rawlog," + bad + "/b.rawlog", "a.rawlog"}})
	{
		EXPECT_NE(
			shadyloc::test::runCommand(
				shadyloc::test::appPath() + " calibrate-alpha " + args + " --linearise none -o " + badOut + "/x", &out),
			0)
			<< args;
		EXPECT_NE(out.find(expect), std::string::npos) << args << ": " << out;
	}
	EXPECT_TRUE(fs::is_empty(bad));
	EXPECT_TRUE(fs::is_empty(badOut));
}

// A camera with a datasheet alpha needs only the 8-bit mapping: --alpha (and
// --beta) are taken as given, no curve is written, and the mapping is
// calibrated at exactly those values.
TEST(InvariantCalibrationApp, KnownAlphaCalibratesOnlyTheMapping)
{
	const auto dir = shadyloc::test::tempDir("calib_app_known");
	std::string args;
	std::vector<cv::Mat> images;
	for (int i = 0; i < 3; i++)
	{
		images.push_back(syntheticScene(80 + i, kSun, kSky, shadowShape(80 + i)));
		const std::string f = dir + "/im" + std::to_string(i) + ".png";
		cv::imwrite(f, images.back());
		args += " --image " + f;
	}
	std::string out;
	ASSERT_EQ(shadyloc::test::runCommand(
				  shadyloc::test::appPath() + " calibrate-alpha" + args +
					  " --linearise none --alpha 0.42 --beta 0.5 --tail 0.002 -o " + dir + "/k",
				  &out),
		0)
		<< out;
	ASSERT_TRUE(fs::exists(dir + "/k.ini"));
	EXPECT_FALSE(fs::exists(dir + "/k_curve.csv"));	 // no estimate, no curve
	const auto inv = filterFromCalibration(dir + "/k.ini");
	ASSERT_TRUE(inv);
	EXPECT_EQ(inv->params().alpha, 0.42);  // the dump writes doubles that read back exactly
	EXPECT_EQ(inv->params().beta, 0.5);
	EXPECT_NE(inv->params().scale, 255.0);
	// The mapping was fitted at the given alpha/beta: 2 x 0.2 % tails clip,
	// 0.1 point of slack for ties at the quantiles of these 8-bit images.
	const auto st = mappingStats(images, inv->params(), 2);
	EXPECT_LE(st.clipped(), 0.005) << st.clipped();
	EXPECT_GT(st.span(), 100.0);

	EXPECT_NE(shadyloc::test::runCommand(
				  shadyloc::test::appPath() + " calibrate-alpha" + args + " --linearise none --beta 0.5 -o " + dir + "/b",
				  &out),
		0);
	EXPECT_NE(out.find("--beta needs --alpha"), std::string::npos) << out;
	EXPECT_NE(shadyloc::test::runCommand(shadyloc::test::appPath() + " calibrate-alpha" + args +
											 " --linearise none --alpha 0.4 --method edges -o " + dir + "/b",
				  &out),
		0);
	EXPECT_NE(out.find("exclude each other"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/b.ini"));
}

// An output inside a folder whose images are all read would be read back as
// an input by the next run (the curve PNG is a colour image): refused, naming
// the folder, before anything is written.
TEST(InvariantCalibrationApp, OutputInsideAnInputFolderIsRefused)
{
	const auto dir = shadyloc::test::tempDir("calib_app_out_in");
	for (int i = 0; i < 3; i++)
	{
		cv::imwrite(dir + "/s" + std::to_string(i) + "_free.png", syntheticScene(90 + i, kSun, kSun, {}));
		cv::imwrite(dir + "/s" + std::to_string(i) + "_shadow1.png", syntheticScene(90 + i, kSun, kSky, shadowShape(90 + i)));
	}
	const auto before = std::distance(fs::directory_iterator(dir), fs::directory_iterator());
	for (const std::string opt : {"--images", "--pairs"})
	{
		std::string out;
		EXPECT_NE(shadyloc::test::runCommand(
					  shadyloc::test::appPath() + " calibrate-alpha " + opt + " " + dir +
						  " --linearise none --bootstrap 0 --no-plot -o " + dir + "/cam",
					  &out),
			0)
			<< opt << ": " << out;
		EXPECT_NE(out.find("'" + dir + "'"), std::string::npos) << opt << ": " << out;
		EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), before) << opt << ": " << out;
	}
}

// A JPEG cut short is an error naming it (cv::imread fills its missing rows
// grey), as in `shadyloc image`.
TEST(InvariantCalibrationApp, TruncatedJpegIsAnError)
{
	const auto dir = shadyloc::test::tempDir("calib_app_cut_jpeg");
	const auto outDir = shadyloc::test::tempDir("calib_app_cut_jpeg_out");
	for (int i = 0; i < 2; i++)
		cv::imwrite(dir + "/im" + std::to_string(i) + ".jpg", syntheticScene(100 + i, kSun, kSky, shadowShape(100 + i)));
	const std::string cut = dir + "/im1.jpg";
	fs::resize_file(cut, fs::file_size(cut) / 2);
	std::string out;
	EXPECT_NE(shadyloc::test::runCommand(
				  shadyloc::test::appPath() + " calibrate-alpha --images " + dir +
					  " --linearise none --bootstrap 0 --no-plot -o " + outDir + "/cam",
				  &out),
		0)
		<< out;
	EXPECT_NE(out.find("im1.jpg"), std::string::npos) << out;
	EXPECT_TRUE(fs::is_empty(outDir)) << out;
}
