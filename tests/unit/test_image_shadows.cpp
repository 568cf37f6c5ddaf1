/* Real shadows (UIUC shadow pairs, Guo et al. CVPR 2011): the invariant
 * channel hides the shadow step far better than monochrome, and the fast path
 * equals the reference path on every pixel of the real images. */
#include "../support/TestSupport.h"

#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/image/ShadowMetrics.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <regex>

using namespace shadyloc::image;
namespace fs = std::filesystem;

namespace
{
struct Pair
{
	std::string name, freePath, shadowPath;
};
std::vector<Pair> shadowPairs()
{
	const auto dir = shadyloc::test::sharedDataDir() + "/shadow-pairs";
	std::vector<Pair> pairs;
	const std::regex re("(p\\d+)_shadow(\\d)\\.jpg");
	for (auto& e : fs::directory_iterator(dir))
	{
		std::smatch m;
		const auto f = e.path().filename().string();
		if (std::regex_match(f, m, re))
			pairs.push_back({m[1].str() + "_s" + m[2].str(), dir + "/" + m[1].str() + "_free.jpg", e.path().string()});
	}
	std::sort(pairs.begin(), pairs.end(), [](auto& a, auto& b) { return a.name < b.name; });
	return pairs;
}
InvariantParams jpegParams()
{
	auto p = InvariantParams::FromAlphaBeta(0.4800, 0.5065);  // paper's values
	p.linearisation = Linearisation::SRGB;	// JPEGs are gamma-encoded
	return p;
}
}  // namespace

// Must-show 2.
TEST(RealShadows, InvariantHidesShadowStepFarBetterThanMono)
{
	SHADYLOC_REQUIRE_SHARED_DATA("shadow-pairs");
	const auto pairs = shadowPairs();
	ASSERT_GE(pairs.size(), 20u);
	const InvariantTransform inv(jpegParams());
	std::vector<double> ratios, invSpreads;
	int invBetter = 0;
	std::printf("%-10s %8s %8s %8s %8s\n", "pair", "mask%", "mono", "invar", "inv/mono");
	for (const auto& p : pairs)
	{
		const cv::Mat f = cv::imread(p.freePath), s = cv::imread(p.shadowPath);
		ASSERT_FALSE(f.empty() || s.empty()) << p.name;
		const cv::Mat mask = shadowMaskFromPair(f, s);
		const double frac = cv::countNonZero(mask) / double(mask.total());
		if (frac < 0.01)
		{
			std::printf("%-10s %7.1f%%  (shadow mask under 1%% of the image: skipped)\n", p.name.c_str(), 100 * frac);
			continue;
		}
		cv::Mat mf, ms, i_f, i_s;
		toMonochrome(f, mf, ChannelOrder::BGR);
		toMonochrome(s, ms, ChannelOrder::BGR);
		inv.apply(f, i_f);
		inv.apply(s, i_s);
		const double rMono = relativeShadowStep(mf, ms, mask).relative();
		const auto sInv = relativeShadowStep(i_f, i_s, mask);
		const double rInv = sInv.relative();
		invSpreads.push_back(sInv.spread);
		const double ratio = rInv / std::max(1e-9, rMono);
		ratios.push_back(ratio);
		invBetter += rInv < rMono;
		std::printf("%-10s %7.1f%% %8.2f %8.2f %8.3f\n", p.name.c_str(), 100 * frac, rMono, rInv, ratio);
	}
	ASSERT_GE(ratios.size(), 20u) << "too few pairs with a usable shadow mask";
	std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
	const double medianRatio = ratios[ratios.size() / 2];
	// A channel that kept no texture would "hide" the shadow trivially: the
	// invariant must keep a real texture spread (in grey levels) on these surfaces.
	std::nth_element(invSpreads.begin(), invSpreads.begin() + invSpreads.size() / 2, invSpreads.end());
	const double medianInvSpread = invSpreads[invSpreads.size() / 2];
	EXPECT_GE(medianInvSpread, 3.0);
	std::printf("median invariant texture spread in the shadow regions: %.1f grey levels\n", medianInvSpread);
	std::printf(
		"pairs used: %zu, invariant better on %d (%.0f%%), median inv/mono step ratio %.3f\n",
		ratios.size(), invBetter, 100.0 * invBetter / ratios.size(), medianRatio);
	// Bars (see the issue note): the invariant channel must win on most pairs
	// and shrink the relative step at least 3-fold in the median.
	EXPECT_GE(invBetter, int(0.75 * ratios.size()));
	EXPECT_LT(medianRatio, 0.33);
}

// Must-show 3: fast path == reference within 1 grey level on every pixel.
TEST(RealShadows, FastPathEqualsReferenceOnEveryPixel)
{
	SHADYLOC_REQUIRE_SHARED_DATA("shadow-pairs");
	for (auto lin : {Linearisation::SRGB, Linearisation::None})
	{
		auto params = jpegParams();
		params.linearisation = lin;
		const InvariantTransform fast(params);
		size_t images = 0;
		for (const auto& p : shadowPairs())
			for (const auto& path : {p.freePath, p.shadowPath})
			{
				const cv::Mat img = cv::imread(path);
				cv::Mat a;
				fast.apply(img, a);
				const cv::Mat b = invariantReference8(img, params);
				ASSERT_LE(cv::norm(a, b, cv::NORM_INF), 1.0) << path;
				images++;
			}
		EXPECT_GT(images, 40u);
	}
}
