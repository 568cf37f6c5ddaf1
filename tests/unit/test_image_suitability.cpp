/* Does a camera suit the invariant channel (docs/calibration.md, "Cameras
 * that suit the invariant channel"): the JPEG block grid and its removal by
 * the chroma handling, the verdict's rules, the command's verdict on the
 * simulator's linear frames and on the real JPEG shadow pairs (UIUC, Guo,
 * Dai and Hoiem, CVPR 2011), and the channel's features on those pairs with
 * and without the chroma handling. */
#include "../support/Sequences.h"
#include "../support/TestSupport.h"

#include <shadyloc/features/IdentityMatches.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/image/CameraSuitability.h>
#include <shadyloc/image/ColourTransforms.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <fstream>
#include <numeric>
#include <regex>

using namespace shadyloc::image;
namespace fs = std::filesystem;

namespace
{
/** A smooth colour scene whose edges fall anywhere (a 37x29 random colour
 * field, bicubically enlarged by a non-integer factor) with fine brightness
 * texture: no structure of its own at 8 or 16 px. Linear 8-bit, BGR. */
cv::Mat offGridScene(uint64_t seed, int w = 320, int h = 240)
{
	cv::RNG rng(seed);
	cv::Mat coarse(29, 37, CV_32FC3), colour, grain(h, w, CV_32F);
	rng.fill(coarse, cv::RNG::UNIFORM, 0.1, 0.8);
	cv::resize(coarse, colour, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
	rng.fill(grain, cv::RNG::UNIFORM, 0.9, 1.1);
	cv::Mat grain3, out;
	cv::merge(std::vector<cv::Mat>{grain, grain, grain}, grain3);
	colour = colour.mul(grain3);
	colour.convertTo(out, CV_8UC3, 255.0);
	return out;
}

/** The image through a JPEG encoder (OpenCV's libjpeg: 4:2:0 chroma). */
cv::Mat jpegRoundTrip(const cv::Mat& img, int quality, const std::string& keepAs = "")
{
	std::vector<uint8_t> bytes;
	cv::imencode(".jpg", img, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
	if (!keepAs.empty()) std::ofstream(keepAs, std::ios::binary).write((const char*)bytes.data(), long(bytes.size()));
	return cv::imdecode(bytes, cv::IMREAD_COLOR);
}

InvariantParams withChroma(ChromaHandling c, Linearisation lin = Linearisation::None)
{
	auto p = InvariantParams::FromAlphaBeta(0.48, 0.52);
	p.linearisation = lin;
	p.chroma_handling = c;
	return p;
}

TAlphaCurve estimate(const std::string& method, double best, double lo, double hi)
{
	TAlphaCurve c;
	c.method = method;
	c.best = best, c.ciLow = lo, c.ciHigh = hi;
	return c;
}

bool hasReason(const TSuitabilityVerdict& v, const std::string& code)
{
	for (const auto& r : v.reasons)
		if (r.code == code) return true;
	return false;
}
}  // namespace

// A synthetic 4:2:0 image: the grid is found (and the header says 4:2:0), and
// the chroma handling removes it. Limits: TSuitabilityLimits (1.15 doubtful).
TEST(InvariantCalibration, JpegBlockGridIsSeenAndTheChromaHandlingRemovesIt)
{
	const auto dir = shadyloc::test::tempDir("suit_grid");
	std::vector<cv::Mat> lossless, jpeg;
	for (uint64_t s = 1; s <= 3; s++)
	{
		lossless.push_back(offGridScene(s));
		jpeg.push_back(jpegRoundTrip(lossless.back(), 75, dir + "/im" + std::to_string(s) + ".jpg"));
	}
	cv::imwrite(dir + "/lossless.png", lossless[0]);
	EXPECT_EQ(jpegChromaSubsampling(dir + "/im1.jpg"), "4:2:0");
	EXPECT_EQ(jpegChromaSubsampling(dir + "/lossless.png"), "");

	const auto none = withChroma(ChromaHandling::None);
	const TBlockGrid clean = blockGridOf(lossless, none), blocky = blockGridOf(jpeg, none);
	const TBlockGrid pre = blockGridOf(jpeg, withChroma(ChromaHandling::Prefilter));
	const TBlockGrid half = blockGridOf(jpeg, withChroma(ChromaHandling::ChromaResolution));
	std::printf(
		"grid ratio 16/8 px: lossless %.3f/%.3f, JPEG q75 %.3f/%.3f, prefilter %.3f/%.3f, chroma resolution %.3f/%.3f\n",
		clean.ratio16, clean.ratio8, blocky.ratio16, blocky.ratio8, pre.ratio16, pre.ratio8, half.ratio16, half.ratio8);
	const TSuitabilityLimits limits;
	EXPECT_LT(std::max(clean.ratio16, clean.ratio8), limits.gridDoubtful);	// measured 1.02
	EXPECT_GE(blocky.ratio16, limits.gridDoubtful);  // measured 1.41 at quality 75 (the UIUC JPEGs: 2.0)
	EXPECT_LT(std::max(pre.ratio16, pre.ratio8), limits.gridDoubtful);

	TSuitabilityEvidence e;
	e.gridMeasured = true;
	e.grid = blocky;
	EXPECT_NE(judgeSuitability(e).verdict, Suitability::Suitable);
	EXPECT_TRUE(hasReason(judgeSuitability(e), "block-grid"));
	e.grid = clean;
	EXPECT_EQ(judgeSuitability(e).verdict, Suitability::Suitable);
}

// The filter's fast path applies the chroma handling exactly as the reference.
TEST(InvariantCalibration, ChromaHandlingFastPathEqualsReference)
{
	const cv::Mat img = jpegRoundTrip(offGridScene(7, 161, 97), 75);  // odd sizes: the half image rounds up
	for (const auto c : {ChromaHandling::Prefilter, ChromaHandling::ChromaResolution})
	{
		const auto p = withChroma(c, Linearisation::SRGB);
		cv::Mat fast;
		InvariantTransform(p).apply(img, fast);
		ASSERT_EQ(fast.size(), img.size());
		EXPECT_LE(cv::norm(fast, invariantReference8(img, p), cv::NORM_INF), 1.0) << toString(c);
	}
}

// The option is read strictly, decides the images, and keeps the recorded
// text of maps made without it.
TEST(InvariantCalibration, ChromaHandlingIsAnImageDefiningOption)
{
	const auto dir = shadyloc::test::tempDir("suit_option");
	auto load = [&](const std::string& keys) {
		std::ofstream(dir + "/f.ini") << "[filters]\npipeline = inv\n[inv]\nclass = CFilterInvariant\n" << keys;
		return shadyloc::filters::FilterPipeline::FromConfigFile(dir + "/f.ini").filters.at(0);
	};
	const auto plain = load(""), pre = load("chroma_handling = prefilter\n");
	const auto wider = load("chroma_handling = prefilter\nchroma_sigma_px = 3\n");
	EXPECT_FALSE(plain->sameImagesAs(*pre));
	EXPECT_FALSE(pre->sameImagesAs(*wider));
	EXPECT_TRUE(plain->sameImagesAs(*load("chroma_sigma_px = 3\n")));  // no effect without prefilter
	EXPECT_EQ(plain->imageOptionsAsIni().find("chroma"), std::string::npos);
	EXPECT_NE(pre->imageOptionsAsIni().find("chroma_handling = prefilter"), std::string::npos);
	EXPECT_THROW(load("chroma_handling = blur\n"), std::exception);
	EXPECT_THROW(load("chroma_handling = prefilter\nchroma_sigma_px = 0\n"), std::exception);
}

// The rules on the estimates: a bound is unsuitable for the estimate used,
// methods apart are doubtful, the entropy takes no part, clipping by share.
TEST(InvariantCalibration, VerdictRulesOnEstimatesAndClipping)
{
	TSuitabilityEvidence e;
	e.search = TAlphaSearch{};
	e.curves = {estimate("pairs", 0.48, 0.45, 0.52), estimate("edges", 0.50, 0.40, 0.55), estimate("entropy", 0.30, 0.29, 0.31)};
	e.chosenMethod = "pairs";
	EXPECT_EQ(judgeSuitability(e).verdict, Suitability::Suitable);

	e.curves[1].best = 0.56;  // 0.08 from pairs
	auto v = judgeSuitability(e);
	EXPECT_EQ(v.verdict, Suitability::Doubtful);
	EXPECT_TRUE(hasReason(v, "methods-disagree"));
	EXPECT_EQ(v.exitCode(), 3);

	e.curves = {estimate("edges", 0.95, 0.94, 0.95)};  // the webcams: at the bound, a tight interval
	e.chosenMethod = "edges";
	v = judgeSuitability(e);
	EXPECT_EQ(v.verdict, Suitability::Unsuitable);
	EXPECT_TRUE(hasReason(v, "at-search-bound"));
	EXPECT_EQ(v.exitCode(), 4);

	e.curves.clear();
	e.saturated = 0.4;
	EXPECT_EQ(judgeSuitability(e).verdict, Suitability::Doubtful);
	e.saturated = 0.6;
	EXPECT_EQ(judgeSuitability(e).verdict, Suitability::Unsuitable);
}

// A stated curve that is not the data's: linear pairs (a shadow scales each
// channel by one factor) written with the sRGB curve drift under "none" and
// not under "srgb". Limits: TSuitabilityLimits (ratio 1.5, floor 0.05).
TEST(InvariantCalibration, ToneCurveOtherThanStatedIsFlagged)
{
	std::vector<TShadowPair> pairs;
	for (uint64_t seed = 11; seed <= 13; seed++)
	{
		cv::Mat linear;
		offGridScene(seed).convertTo(linear, CV_32FC3, 1.0 / 255.0);
		cv::Mat shadowed = linear.clone();
		shadowed(cv::Rect(60, 40, 160, 120)) = shadowed(cv::Rect(60, 40, 160, 120)).mul(cv::Scalar(0.35, 0.3, 0.25));
		auto srgb8 = [](const cv::Mat& lin) {
			cv::Mat out(lin.size(), CV_8UC3);
			for (int i = 0; i < int(lin.total() * 3); i++)
			{
				const double v = lin.ptr<float>()[i];
				out.ptr<uint8_t>()[i] = cv::saturate_cast<uint8_t>(
					255.0 * (v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055));
			}
			return out;
		};
		pairs.push_back({"s" + std::to_string(seed), srgb8(linear), srgb8(shadowed)});
	}
	TCalibrationInput stated;
	stated.linearisation = Linearisation::None;
	TSuitabilityEvidence e;
	e.tone = toneCurveDrifts(pairs, stated);
	ASSERT_EQ(e.tone.size(), 2u);
	std::printf("drift stated none %.3f, srgb %.3f\n", e.tone[0].drift, e.tone[1].drift);
	EXPECT_TRUE(hasReason(judgeSuitability(e), "tone-curve"));
	stated.linearisation = Linearisation::SRGB;
	e.tone = toneCurveDrifts(pairs, stated);
	std::printf("drift stated srgb %.3f, none %.3f\n", e.tone[0].drift, e.tone[1].drift);
	EXPECT_LT(e.tone[0].drift, 0.02);  // 8-bit quantisation only
	EXPECT_EQ(judgeSuitability(e).verdict, Suitability::Suitable);
}

// The simulator's linear frames (the default data) suit the channel: the
// command says so and exits 0.
TEST(InvariantCalibrationApp, VerdictSuitableOnTheSimulatorsLinearFrames)
{
	// The simulator's noon run as the ctest fixture renders it (or rendered
	// here outside ctest): linear, lossless, so it must pass.
	const std::string rawlog = shadyloc::test::simSequenceDir("noon") + "/noon.rawlog";
	const auto dir = shadyloc::test::tempDir("suit_sim");
	std::string out;
	const int rc = shadyloc::test::runCommand(
		shadyloc::test::appPath() + " calibrate-alpha --rawlog " + rawlog +
			" --every 3 --max-frames 10 --linearise none --bootstrap 20 --no-plot -o " + dir + "/sim",
		&out);
	EXPECT_EQ(rc, 0) << out;
	EXPECT_NE(out.find("\nverdict: suitable\n"), std::string::npos) << out;
	EXPECT_NE(out.find("\nresult: alpha = "), std::string::npos) << out;
	EXPECT_EQ(out.find("reason:"), std::string::npos) << out;
}

namespace
{
std::vector<std::pair<std::string, std::string>> jpegShadowPairs()
{
	const auto dir = shadyloc::test::sharedDataDir() + "/shadow-pairs";
	std::vector<std::pair<std::string, std::string>> pairs;
	const std::regex re("(p\\d+)_shadow\\d\\.jpg");
	for (const auto& e : fs::directory_iterator(dir))
	{
		std::smatch m;
		const std::string f = e.path().filename().string();
		if (std::regex_match(f, m, re)) pairs.emplace_back(dir + "/" + m[1].str() + "_free.jpg", e.path().string());
	}
	std::sort(pairs.begin(), pairs.end());
	return pairs;
}
}  // namespace

// Must-show 4: the verdict on the JPEG shadow pairs. No confident number.
TEST(InvariantCalibrationReal, VerdictFlagsTheJpegShadowPairs)
{
	SHADYLOC_REQUIRE_SHARED_DATA("shadow-pairs");
	const auto dir = shadyloc::test::tempDir("suit_real");
	std::string out;
	const int rc = shadyloc::test::runCommand(
		shadyloc::test::appPath() + " calibrate-alpha --pairs " + shadyloc::test::sharedDataDir() +
			"/shadow-pairs --linearise srgb --step 0.01 --bootstrap 20 --no-plot -o " + dir + "/uiuc",
		&out);
	EXPECT_EQ(rc, 4) << out;
	EXPECT_NE(out.find("\nverdict: unsuitable\n"), std::string::npos) << out;
	EXPECT_NE(out.find("reason: block-grid (unsuitable)"), std::string::npos) << out;
	EXPECT_NE(out.find("reason: chroma-subsampled"), std::string::npos) << out;
	EXPECT_EQ(out.find("\nresult: alpha = "), std::string::npos) << out;
	EXPECT_NE(out.find("NOT a confident estimate"), std::string::npos) << out;
	std::ifstream ini(dir + "/uiuc.ini");
	const std::string text((std::istreambuf_iterator<char>(ini)), std::istreambuf_iterator<char>());
	EXPECT_NE(text.find("# Suitability verdict: unsuitable (block-grid"), std::string::npos) << text;
}

// Must-show 4: the invariant channel's features on the JPEG pairs, shadowed
// image against shadow-free, with and without the chroma handling, and the
// keypoints' pile-up on the 16-px grid. Tripod: at the same place, where a
// block corner matches itself (the two images share the grid). Moved: the
// shadowed invariant cropped 5 px right and 3 px down, so the grids of the
// two images lie at different places of the scene, as under camera motion.
// The table is docs/calibration.md's.
TEST(RealShadows, ChromaHandlingOnTheJpegPairs)
{
	SHADYLOC_REQUIRE_SHARED_DATA("shadow-pairs");
	const auto pairs = jpegShadowPairs();
	ASSERT_GE(pairs.size(), 40u);
	struct TRow
	{
		std::string name;
		InvariantParams params;
		long keypoints = 0, correct = 0, correctOffGrid = 0, moved = 0;
		double nearGrid = 0, offGrid = 0;
		std::vector<int> movedPerPair;
	};
	auto row = [](const std::string& name, const InvariantParams& p) {
		TRow r;
		r.name = name, r.params = p;
		return r;
	};
	auto prefilter = [&](double sigma) {
		auto p = withChroma(ChromaHandling::Prefilter, Linearisation::SRGB);
		p.chroma_sigma_px = sigma;
		return row("prefilter " + std::to_string(sigma).substr(0, 3) + " px", p);
	};
	std::vector<TRow> rows = {
		row("none", withChroma(ChromaHandling::None, Linearisation::SRGB)), prefilter(1.0), prefilter(1.5), prefilter(2.0),
		prefilter(3.0), row("chroma_resolution", withChroma(ChromaHandling::ChromaResolution, Linearisation::SRGB))};
	shadyloc::features::TIdentityMatchOptions movedBy;
	movedBy.shift = {5, 3};
	// The monochrome channel for scale, at its own settings of config/vo.ini.
	shadyloc::features::TIdentityMatchOptions monoOptions;
	monoOptions.fastThreshold = 12, monoOptions.presmoothSigma = 0;
	monoOptions.shift = movedBy.shift;
	std::vector<int> monoMoved;
	std::vector<cv::Mat> shadowImages;
	for (const auto& [freePath, shadowPath] : pairs)
	{
		const cv::Mat f = cv::imread(freePath), s = cv::imread(shadowPath);
		ASSERT_FALSE(f.empty() || s.empty()) << shadowPath;
		shadowImages.push_back(s);
		const cv::Rect moved(5, 3, s.cols - 5, s.rows - 3), kept(0, 0, s.cols - 5, s.rows - 3);
		cv::Mat ms, mf;
		toMonochrome(s, ms, ChannelOrder::BGR), toMonochrome(f, mf, ChannelOrder::BGR);
		monoMoved.push_back(shadyloc::features::identityMatches(ms(moved).clone(), mf(kept).clone(), monoOptions).correct);
		for (auto& r : rows)
		{
			const InvariantTransform inv(r.params);
			cv::Mat a, b;
			inv.apply(s, a), inv.apply(f, b);
			const auto tripod = shadyloc::features::identityMatches(a, b);
			r.keypoints += tripod.keypoints, r.correct += tripod.correct, r.correctOffGrid += tripod.correctOffGrid;
			r.nearGrid += tripod.coordsNearGrid, r.offGrid += tripod.coordsOffGrid;
			const auto m = shadyloc::features::identityMatches(a(moved).clone(), b(kept).clone(), movedBy);
			r.moved += m.correct;
			r.movedPerPair.push_back(m.correct);
		}
	}
	std::printf(
		"%-18s %9s %7s %7s %14s %7s %13s %13s\n", "chroma_handling", "keypoints", "grid16", "pile-up", "tripod correct",
		"off grid", "moved correct", "median/pair");
	for (auto& r : rows)
	{
		auto& c = r.movedPerPair;
		std::nth_element(c.begin(), c.begin() + long(c.size() / 2), c.end());
		std::printf(
			"%-18s %9ld %7.2f %7.2f %14ld %7ld %13ld %13d\n", r.name.c_str(), r.keypoints,
			blockGridOf(shadowImages, r.params).ratio16, shadyloc::features::gridPileUp(r.nearGrid, r.offGrid), r.correct,
			r.correctOffGrid, r.moved, c[c.size() / 2]);
	}
	std::nth_element(monoMoved.begin(), monoMoved.begin() + long(monoMoved.size() / 2), monoMoved.end());
	std::printf(
		"monochrome (for scale): moved correct %d, median per pair %d\n",
		std::accumulate(monoMoved.begin(), monoMoved.end(), 0), monoMoved[monoMoved.size() / 2]);
	const auto pileUp = [](const TRow& r) { return shadyloc::features::gridPileUp(r.nearGrid, r.offGrid); };
	const auto gridExcess = [&](const TRow& r) { return blockGridOf(shadowImages, r.params).ratio16 - 1; };
	// The grid is in the images and draws keypoints (measured: grid 2.45,
	// pile-up 2.21); the default prefilter (row 2, 1.5 px) takes more than
	// half of the grid's excess and a third of the pile-up's away (measured
	// 1.30 and 1.52), with margins for other builds' rounding.
	EXPECT_GT(gridExcess(rows[0]), 1.0);
	EXPECT_GT(pileUp(rows[0]), 2.0);
	EXPECT_LT(gridExcess(rows[2]), 0.5 * gridExcess(rows[0]));
	EXPECT_LT(pileUp(rows[2]) - 1, 0.67 * (pileUp(rows[0]) - 1));
}
