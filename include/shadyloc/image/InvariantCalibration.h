/* ShadyLoc — calibrating the illumination-invariant transform from data, for
 * cameras without a datasheet (see docs/calibration.md).
 *
 * With beta = 1 - alpha the invariant is a projection in log-chromaticity
 * space: writing x = log(R1/R3) (blue over red) and y = log(R2/R3) (green over
 * red),
 *
 *     I = log R2 - alpha log R1 - (1 - alpha) log R3 = y - alpha * x,
 *
 * so every method below looks for the one direction along which a change of
 * daylight moves a surface's chromaticity (x, y): alpha = dy/dx along it.
 * That is all such data can identify. alpha and beta separately (the paper's
 * two-parameter form, alpha + beta != 1) would need intensity changes that
 * vary independently of colour-temperature changes; in real data shadows are
 * darker *and* bluer together, and exposure changes are pure intensity, which
 * any alpha + beta != 1 would leak into I. So all methods fix beta = 1 - alpha.
 *
 * Methods (each gives a curve over alpha, its minimum and a bootstrap
 * confidence interval over images):
 *  - pairs: shadow / no-shadow images of the same view. alpha minimising the
 *    shadow's step relative to the texture (relativeShadowStepOfValues(),
 *    the metric of docs/invariant.md) inside the shadow mask.
 *  - entropy: ordinary images. The projection direction of minimum entropy of
 *    the projected values (Finlayson, Drew & Lu, "Entropy minimization for
 *    shadow removal", IJCV 85(1), 2009), bin width by Scott's rule over the
 *    middle 90 % of the data, as they do.
 *  - same view, different light: image pairs of one view under two lights
 *    (two traversals of a route at the same pose, a stereo eye re-shot under
 *    another lamp). alpha making the two invariant images agree: the median
 *    change of the unit-norm invariant over the pixels whose chromaticity
 *    changed.
 *  - edges (unsupervised, ours): the direction in which edges move the
 *    chromaticity as they get darker; see alphaByEdgeDirections().
 * And the 8-bit mapping (scale, offset): robust percentiles of I over the
 * calibration images (calibrateMapping()).
 */
#pragma once

#include <shadyloc/image/ColourTransforms.h>

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace shadyloc::image
{
/** How calibration images are read and which pixels are trusted. */
struct TCalibrationInput
{
	ChannelOrder order = ChannelOrder::BGR;	 //!< memory order of the 8-bit images
	/** Input, not estimated: the camera's transfer curve must be known (the
	 * log-chromaticity geometry is only linear for linear responses). */
	Linearisation linearisation = Linearisation::None;
	double gamma = 2.2;	 //!< exponent when linearisation == Gamma
	/** A pixel with any channel below this code value is "dark" and skipped:
	 * its logs are noise and quantisation. */
	int minCode = 8;
	/** A pixel with any channel at or above this code value is "saturated"
	 * and skipped: a clipped channel breaks the ratios (blown sky, highlights). */
	int maxCode = 250;
	/** Fraction of image rows at the top that are skipped (0 = none); for a
	 * forward-looking vehicle camera the sky. A clear sky is close to a
	 * black body and does not bias the estimate, but clouds (grey, not lit by
	 * the scene's light) and blown-out sky do; saturation catches the latter. */
	double skipTopFraction = 0.0;
	/** Every stride-th pixel in x and y is sampled (entropy, mapping). */
	int stride = 2;

	void validate() const;	//!< std::invalid_argument naming the field
	InvariantParams params(double alpha) const;	 //!< alpha, beta = 1 - alpha, this input, default mapping
};

/** A curve over alpha and its minimum. */
struct TAlphaCurve
{
	std::vector<double> alpha;	//!< grid, increasing
	std::vector<double> cost;  //!< the method's criterion at each alpha (lower = better)
	double best = 0;  //!< argmin (refined by a least-squares parabola around the grid minimum, TAlphaSearch::refineHalfWidth)
	double ciLow = 0, ciHigh = 0;  //!< 95 % bootstrap interval of best (percentiles 2.5, 97.5)
	int items = 0;	//!< images or pairs the estimate used
	int bootstrapRounds = 0;
	std::string method;	 //!< "pairs", "same-view", "runs", "edges", "entropy"
	std::string costName;  //!< what cost means, for plots and reports
};

/** Options shared by the estimators. */
struct TAlphaSearch
{
	double alphaMin = 0.05, alphaMax = 0.95;  //!< search range
	double step = 0.005;  //!< grid spacing
	/** Half-width (alpha units) of the window around the grid minimum over
	 * which a parabola is fitted by least squares to refine it; at or below
	 * step, the three-point parabola through the minimum and its neighbours.
	 * Wider windows smooth the curves' small-scale roughness, so the
	 * estimate does not depend on the grid step (docs/calibration.md). */
	double refineHalfWidth = 0.02;
	int bootstrapRounds = 200;	//!< 0 = no confidence interval
	uint32_t seed = 1;	//!< bootstrap resampling seed
	void validate() const;
	std::vector<double> grid() const;
};

// ---- 1. shadow / no-shadow pairs --------------------------------------------
/** One tripod-aligned pair: the same view without and with a cast shadow. */
struct TShadowPair
{
	std::string name;  //!< for messages
	cv::Mat free, shadow;  //!< 8-bit colour, TCalibrationInput::order
};

/** Shadow mask of a pair with the criterion of shadowMaskFromPair() (every
 * channel's linear response dropped by more than e^minLogDrop; eroded) but
 * under the input's linearisation, plus the input's dark/saturated rule. */
cv::Mat shadowMask(const TShadowPair& p, const TCalibrationInput& in, double minLogDrop = 0.4, int erodeRadius = 3);

/** How the pairs' relative shadow steps are combined into one curve. */
enum class PairAverage
{
	/** Arithmetic mean (default): each pair's curve is shallow near the
	 * common minimum and the mean follows the bulk of the pairs. */
	Arithmetic,
	/** Geometric mean (the mean of logs): a pair whose step nearly vanishes
	 * at its own alpha makes a deep, narrow dip that pulls the minimum
	 * towards it; kept for comparison (docs/calibration.md). */
	Geometric
};

/** alpha minimising the mean over pairs of the relative shadow step
 * (relativeShadowStepOfValues() on I * 255: grey levels of the default
 * scale). Pairs whose mask covers less than minMaskFraction of the image are
 * left out (named in *skipped). Throws if fewer than 1 pair remains. */
TAlphaCurve alphaFromShadowPairs(
	const std::vector<TShadowPair>& pairs, const TCalibrationInput& in, const TAlphaSearch& s = {},
	double minMaskFraction = 0.01, std::vector<std::string>* skipped = nullptr,
	PairAverage average = PairAverage::Arithmetic);

// ---- 2. unsupervised: entropy minimisation -----------------------------------
/** Log-chromaticities (x = log(R1/R3), y = log(R2/R3)) of the trusted pixels
 * of a set of images, with the image each came from. */
struct TChromaSamples
{
	std::vector<float> x, y;
	std::vector<uint32_t> imageStart;  //!< samples of image i: [imageStart[i], imageStart[i+1])
	size_t images() const { return imageStart.empty() ? 0 : imageStart.size() - 1; }
	size_t size() const { return x.size(); }
};

/** Samples every in.stride-th pixel of each image (8-bit colour), skipping
 * dark, saturated and top rows as in says. Table-driven (one log table). */
TChromaSamples chromaSamples(const std::vector<cv::Mat>& images, const TCalibrationInput& in);

/** How the entropy finds the middle 90 % of the projected values. */
enum class EntropyQuantiles
{
	/** Default: one pass into a fine histogram (8192 bins over the values
	 * range) gives the quantiles, the spread and Scott's bins. */
	Histogram,
	/** Exact quantiles by partial sorts: the reference for tests and the
	 * benchmark, nearly 3x slower (bench_calibration). */
	Sorted
};

/** Finlayson-Drew-Lu entropy over alpha of the projected values y - alpha x.
 * Bin width by Scott's rule (3.49 sigma N^-1/3) over the middle 90 % of the
 * projected data, as in their paper; the histogram is over that middle 90 %.
 * Bootstrap: images are resampled and the pooled histogram recomputed. */
TAlphaCurve alphaByEntropy(
	const TChromaSamples& samples, const TAlphaSearch& s = {}, EntropyQuantiles quantiles = EntropyQuantiles::Histogram);

// ---- 2b. unsupervised: shadow edges are darker and bluer ---------------------
/** Differences between each sampled pixel (every in.stride-th) and the
 * pixel `separation` px to its right and below, where both are trusted and log-brightness changes by more than
 * minLogEdge: the change of (x, y) log-chromaticity and of log-brightness
 * L = (log R1 + log R2 + log R3) / 3 across the edge. */
struct TEdgeSamples
{
	std::vector<float> dx, dy, dl;
	std::vector<uint32_t> imageStart;  //!< samples of image i: [imageStart[i], imageStart[i+1])
	size_t images() const { return imageStart.empty() ? 0 : imageStart.size() - 1; }
	size_t size() const { return dx.size(); }
};
/** separation: wider than the JPEG/Bayer chroma blur (4:2:0 chroma has half
 * the resolution), so that the brightness and the chromaticity step of one
 * edge both fall between the two pixels. */
TEdgeSamples edgeSamples(
	const std::vector<cv::Mat>& images, const TCalibrationInput& in, int separation = 4, double minLogEdge = 0.1);

/** alpha from the direction in which edges move the log-chromaticity as they
 * get darker. Across a shadow edge the surface stays and the light changes,
 * so (x, y) moves along the illuminant direction (1, alpha), and towards +x
 * (bluer) as the brightness drops. Material edges move it in directions
 * unrelated to their brightness step. Per image: a kernel density (von Mises,
 * ~3.4 degrees) of the directions of sign-aligned chromaticity steps
 * (|step| >= 0.02), each weighted by its brightness step; the cost is minus
 * that density at the direction (1, alpha), averaged over images. Unlike
 * the entropy it does not reward directions along which the scene's colours
 * happen to be concentrated, nor the lattice directions of 8-bit
 * quantisation (see docs/calibration.md for the comparison).
 *
 * maxChromaPerBrightness: only steps whose log-chromaticity change is at
 * most this many times their log-brightness change count. A change of
 * daylight is a brightness change first: full sun to sky light drops the
 * log-brightness by log(1 + sun/sky) ~ 1.1-2.3, while the chromaticity moves
 * by the sun-sky colour-temperature difference, ~0.5-0.8 in these units
 * for Wien's model of a 470/540/620 nm camera (5800 K -> 14000 K). Material
 * edges often change colour more than brightness, and those were what
 * biased this criterion on the simulator (docs/calibration.md: without the
 * bound, pass a huge value, 0.07-0.35 off the reference; with 1, <= 0.056). */
TAlphaCurve alphaByEdgeDirections(
	const TEdgeSamples& samples, const TAlphaSearch& s = {}, double maxChromaPerBrightness = 1.0);

// ---- 3. same view, different light ------------------------------------------
/** Two images of one view (pixel-aligned) under different light. */
struct TSameViewPair
{
	std::string name;
	cv::Mat a, b;  //!< 8-bit colour, same size
};

/** alpha minimising the geometric mean over pairs of the median change of
 * the unit-norm invariant (y - alpha x) / sqrt(1 + alpha^2) between the two
 * images: the perpendicular distance of each pixel's chromaticity change
 * from the illuminant line (1, alpha), a robust line fit through the origin.
 * Pixels: trusted in both images, chromaticity (x, y) moved by more than
 * minChromaChange (log units; those whose light did not change carry no
 * information). Intensity changes (exposure) cancel in I. Pairs with fewer
 * than 500 such pixels are skipped (named in *skipped). */
TAlphaCurve alphaFromSameView(
	const std::vector<TSameViewPair>& pairs, const TCalibrationInput& in, const TAlphaSearch& s = {},
	double minChromaChange = 0.03, std::vector<std::string>* skipped = nullptr);

/** Log-chromaticities x = log(R1/R3), y = log(R2/R3) of the same surface
 * points under two lights (a, b): what the same-view criterion reads. */
struct TChromaChanges
{
	std::string name;  //!< for messages (a pair, a matched frame pair)
	std::vector<float> xa, ya, xb, yb;
	size_t size() const { return xa.size(); }
};

/** The same-view criterion (alphaFromSameView()) on given changes, one
 * curve per item; items with fewer than minSamples points whose
 * chromaticity moved by more than minChromaChange are skipped (named in
 * *skipped). The curve is named `method`. */
TAlphaCurve alphaFromChromaChanges(
	const std::vector<TChromaChanges>& items, const TAlphaSearch& s, double minChromaChange, size_t minSamples,
	const std::string& method, std::vector<std::string>* skipped = nullptr);

// ---- 3b. two runs of one route under different light -------------------------
/** How frames of two runs are put in correspondence (correspondencesAcrossRuns()). */
struct TCrossRunMatching
{
	int features = 3000;  //!< ORB keypoints per frame (on the monochrome image)
	/** The search: every B frame is first matched with this many keypoints
	 * (cheap), and only the `candidates` best are matched with all. */
	int coarseFeatures = 500, candidates = 3;
	double ratio = 0.9;	 //!< Lowe's ratio test on the two nearest Hamming distances
	double ransacPx = 1.0;	//!< fundamental-matrix RANSAC threshold [px]
	int minInliers = 40;  //!< a frame pair with fewer RANSAC inliers is not used (wrong pairings measured up to 34, true ones from 44)
	int window = 4;	 //!< colours sampled pixel for pixel over the (2 window + 1)^2 px around each inlier
	double maxRoughness = 0.1;	//!< ... where no channel steps by more than this (log) to a 4-neighbour
	void validate() const;
};

/** Same-view data from two recordings of the same places under different
 * light, with no poses needed: every frame of run A is matched (ORB,
 * ratio test, fundamental-matrix RANSAC; OpenCV) against every frame of run
 * B (coarsely, then the best candidates in full), and the B frame with the
 * most inliers, if at least minInliers, gives
 * one item: the colours of the pixels around each inlier, taken pixel for
 * pixel in both images where both are locally flat (so that a pixel of
 * misregistration samples the same surface; ORB finds corners, whose own
 * pixels are not flat), trusted in both and below the skipped top rows.
 * A line per A frame (its match and inlier count, or why not) goes to
 * `progress` as soon as that frame is done, e.g. for a long run's output. */
std::vector<TChromaChanges> correspondencesAcrossRuns(
	const std::vector<cv::Mat>& runA, const std::vector<cv::Mat>& runB, const TCalibrationInput& in,
	const TCrossRunMatching& m = {}, const std::function<void(const std::string&)>& progress = {});

// ---- 4. the 8-bit mapping ---------------------------------------------------
/** Mapping statistics of I over a set of images at given parameters. */
struct TMappingStats
{
	double clipLow = 0, clipHigh = 0;  //!< share of pixels mapped to 0 / 255 (fraction)
	double p1 = 0, p99 = 0;	 //!< 1st and 99th percentile of the 8-bit output (grey levels, unclamped)
	double clipped() const { return clipLow + clipHigh; }
	double span() const { return p99 - p1; }  //!< grey levels between the 1st and 99th percentiles
};

/** Share of clipped pixels and percentile span of the 8-bit invariant of
 * every stride-th pixel (all pixels count, dark and saturated too: they are
 * what gets clipped). */
TMappingStats mappingStats(const std::vector<cv::Mat>& images, const InvariantParams& p, int stride = 2);

/** The 8-bit mapping from robust quantiles of I over the images: the
 * tailShare and 1 - tailShare quantiles go to grey levels 0.5 and 254.5, so
 * that about 2 * tailShare of the calibration pixels clip. Linear (scale and
 * offset, in p's form out = scale * (I + offset)) when that gives the 1st-99th
 * percentiles at least minSpan grey levels; otherwise those percentiles get
 * exactly minSpan levels and the tails beyond them are compressed at one
 * common slope (knee_* and tail_slope_* of InvariantParams). minSpan 210 is
 * the goal of 200 with a 5 % margin for live frames, which are not the
 * calibration images. Returns p with the mapping replaced. */
InvariantParams calibrateMapping(
	const std::vector<cv::Mat>& images, InvariantParams p, double tailShare = 0.002, int stride = 2,
	double minSpan = 210.0);

/** The green peak wavelength that gives alpha with blue and red peaks l1, l3
 * (any unit) in 1/l2 = alpha/l1 + (1 - alpha)/l3: the wavelength form of a
 * calibrated alpha, for reports. */
double equivalentGreenPeak(double alpha, double l1, double l3);

}  // namespace shadyloc::image
