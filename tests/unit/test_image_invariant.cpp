/* Tests of the colour transforms: physics of the invariant, fast vs
 * reference path, parameterisations. */
#include <shadyloc/image/ColourTransforms.h>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <cmath>
#include <random>
#include <vector>

using namespace shadyloc::image;

namespace
{
// Planck's law: spectral radiance of a black body at wavelength l (m), T (K),
// up to a constant factor (absorbed in intensity).
double planck(double l, double T)
{
	constexpr double h = 6.62607015e-34, c = 2.99792458e8, k = 1.380649e-23;
	return (2 * h * c * c / std::pow(l, 5)) / (std::exp(h * c / (l * k * T)) - 1.0);
}
// Narrowband (Dirac) sensor at peak wavelength l: response = I0 * E(l,T) * S(l).
double response(double l, double T, double I0, double reflectance)
{
	return I0 * planck(l, T) * reflectance;
}
}  // namespace

// Must-show 1: with beta from the wavelength constraint, the invariant does
// not depend on the colour temperature; with beta = 1 - alpha it does not depend
// on intensity either; log-grey changes with both.
TEST(InvariantPhysics, IndependentOfPlanckianIlluminant)
{
	const double l1 = 470e-9, l2 = 540e-9, l3 = 620e-9;	 // blue, green, red peaks
	const auto p = InvariantParams::FromWavelengths(l1, l2, l3);
	ASSERT_NEAR(p.alpha + p.beta, 1.0, 1e-12);
	ASSERT_NEAR(1 / l2, p.alpha / l1 + p.beta / l3, 1e-6 / l2);

	// Three materials (reflectance at the three peaks).
	const std::vector<std::array<double, 3>> materials = {
		{0.08, 0.35, 0.12}, {0.45, 0.40, 0.30}, {0.05, 0.09, 0.20}};
	const std::vector<double> temps = {2500, 4000, 5500, 6500, 10000, 20000};	 // K
	const std::vector<double> intensities = {1e-14, 1e-13, 5e-12};

	for (const auto& m : materials)
	{
		double invMin = 1e9, invMax = -1e9, greyMin = 1e9, greyMax = -1e9;
		for (double T : temps)
			for (double I0 : intensities)
			{
				// Wien's approximation is what the derivation assumes; Planck's
				// law departs from it by exp(-hc/lkT), below 1e-6 only for
				// hc/lkT > 14, i.e. T < ~1600 K at 620 nm. Use Wien here to test
				// the algebra to 1e-6, and Planck below with its tolerance.
				auto wien = [&](double l, double r) {
					constexpr double h = 6.62607015e-34, c = 2.99792458e8, k = 1.380649e-23;
					return I0 * (2 * h * c * c / std::pow(l, 5)) * std::exp(-h * c / (l * k * T)) * r;
				};
				const double R1 = wien(l1, m[0]), R2 = wien(l2, m[1]), R3 = wien(l3, m[2]);
				const double I = std::log(R2) - p.alpha * std::log(R1) - p.beta * std::log(R3);
				const double g = std::log((R1 + R2 + R3) / 3);
				invMin = std::min(invMin, I), invMax = std::max(invMax, I);
				greyMin = std::min(greyMin, g), greyMax = std::max(greyMax, g);
			}
		EXPECT_LT(invMax - invMin, 1e-6) << "invariant changed with the illuminant";
		EXPECT_GT(greyMax - greyMin, 1.0) << "log-grey should change a lot";
	}
}

TEST(InvariantPhysics, ColourTemperatureOnlyWithPaperAlphaBeta)
{
	// The paper's alpha, beta satisfy the wavelength constraint for some l1,l2,l3
	// but not beta = 1 - alpha: the image is invariant to colour temperature,
	// not to intensity. Choose l2 from the constraint for given l1, l3.
	const auto p = InvariantParams::FromAlphaBeta(0.4800, 0.5065);
	const double l1 = 470e-9, l3 = 620e-9;
	const double l2 = 1.0 / (p.alpha / l1 + p.beta / l3);
	double mn = 1e9, mx = -1e9;
	for (double T : {3000.0, 5000.0, 6500.0, 12000.0})
	{
		const double I = std::log(response(l2, T, 1e-13, 0.3)) -
						 p.alpha * std::log(response(l1, T, 1e-13, 0.2)) -
						 p.beta * std::log(response(l3, T, 1e-13, 0.4));
		mn = std::min(mn, I), mx = std::max(mx, I);
	}
	// Planck vs Wien residual at these temperatures is < 1e-3 in log.
	EXPECT_LT(mx - mn, 2e-3);
}

TEST(InvariantParamsTest, WavelengthsGiveAlphaAndValidation)
{
	// (1/540 - 1/620) / (1/470 - 1/620) = 0.46420 (worked by hand).
	const auto p = InvariantParams::FromWavelengths(470, 540, 620);
	EXPECT_NEAR(p.alpha, 0.46420, 1e-4);
	EXPECT_NEAR(p.beta, 1 - 0.46420, 1e-4);
	EXPECT_THROW(InvariantParams::FromWavelengths(540, 470, 620), std::invalid_argument);
	InvariantParams bad;
	bad.scale = -1;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
	EXPECT_THROW(parseChannelOrder("grb"), std::invalid_argument);
	EXPECT_THROW(parseLinearisation("log"), std::invalid_argument);
}

TEST(InvariantTransformTest, FastEqualsReferenceOnAllColoursAllLinearisations)
{
	// Every 8-bit colour on a coarse grid plus random ones; every mode.
	cv::Mat img(64, 1024, CV_8UC3);
	std::mt19937 rng(7);
	std::uniform_int_distribution<int> u(0, 255);
	for (int y = 0; y < img.rows; y++)
		for (int x = 0; x < img.cols; x++)
			img.at<cv::Vec3b>(y, x) = cv::Vec3b(u(rng), u(rng), u(rng));
	img.at<cv::Vec3b>(0, 0) = cv::Vec3b(0, 0, 0);
	img.at<cv::Vec3b>(0, 1) = cv::Vec3b(255, 255, 255);
	for (auto lin : {Linearisation::None, Linearisation::SRGB, Linearisation::Gamma})
		for (auto order : {ChannelOrder::BGR, ChannelOrder::RGB})
		{
			auto p = InvariantParams::FromAlphaBeta(0.48, 0.5065);
			p.linearisation = lin;
			p.order = order;
			p.scale = 60;  // a smaller scale: fewer saturated pixels, a harder test
			const cv::Mat ref = invariantReference8(img, p);
			cv::Mat fast;
			InvariantTransform(p).apply(img, fast);
			cv::Mat diff;
			cv::absdiff(ref, fast, diff);
			double mx;
			cv::minMaxLoc(diff, nullptr, &mx);
			EXPECT_LE(mx, 1.0) << "lin=" << toString(lin) << " order=" << toString(order);
		}
}

// Compressed tails: the fast path's fixed-point tails agree with the
// reference within one level, the middle is untouched, and the output is
// monotone in I (a tone curve, not a fold).
TEST(InvariantTransformTest, CompressedTailsFastEqualsReferenceAndMiddleIsLinear)
{
	cv::Mat img(64, 1024, CV_8UC3);
	std::mt19937 rng(11);
	std::uniform_int_distribution<int> u(0, 255);
	for (int y = 0; y < img.rows; y++)
		for (int x = 0; x < img.cols; x++) img.at<cv::Vec3b>(y, x) = cv::Vec3b(u(rng), u(rng), u(rng));
	auto lin = InvariantParams::FromAlphaBeta(0.46, 0.54);
	lin.linearisation = Linearisation::SRGB;
	lin.scale = 90;
	auto tone = lin;
	tone.knee_low = 40.5;
	tone.knee_high = 200.25;
	tone.tail_slope_low = 0.3;
	tone.tail_slope_high = 0.55;
	ASSERT_TRUE(tone.hasCompressedTails());
	ASSERT_FALSE(tone.sameImageAs(lin));
	cv::Mat fast, fastLin;
	InvariantTransform(tone).apply(img, fast);
	InvariantTransform(lin).apply(img, fastLin);
	cv::Mat diff;
	cv::absdiff(invariantReference8(img, tone), fast, diff);
	double mx;
	cv::minMaxLoc(diff, nullptr, &mx);
	EXPECT_LE(mx, 1.0);
	const cv::Mat I = invariantReferenceFloat(img, lin);
	int inMiddle = 0, inTails = 0;
	for (int y = 0; y < img.rows; y++)
		for (int x = 0; x < img.cols; x++)
		{
			const double g = lin.scale * (I.at<float>(y, x) + lin.offset);
			if (g > tone.knee_low + 1 && g < tone.knee_high - 1)
			{
				inMiddle++;
				EXPECT_EQ(fast.at<uint8_t>(y, x), fastLin.at<uint8_t>(y, x));
			}
			else if (g < tone.knee_low - 10 || g > tone.knee_high + 10)
			{
				inTails++;
				// Pulled towards the knee: the compressed tail clips less.
				EXPECT_LE(std::abs(tone.toGrey(I.at<float>(y, x)) - 127.0), std::abs(g - 127.0));
			}
		}
	EXPECT_GT(inMiddle, 1000);
	EXPECT_GT(inTails, 1000);
	for (double a = -4; a < 4; a += 0.01) EXPECT_LT(tone.toGrey(a), tone.toGrey(a + 0.01));
	auto bad = tone;
	bad.tail_slope_low = 0;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
	bad = tone;
	bad.knee_high = bad.knee_low;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(InvariantTransformTest, ZeroPixelsAreFiniteAndOrderMatters)
{
	cv::Mat img(1, 2, CV_8UC3);
	img.at<cv::Vec3b>(0, 0) = cv::Vec3b(0, 0, 0);
	img.at<cv::Vec3b>(0, 1) = cv::Vec3b(200, 100, 50);	// BGR: blue-ish
	// Unequal weights, so that swapping blue and red changes I.
	const auto p = InvariantParams::FromAlphaBeta(0.3, 0.7);
	const cv::Mat f = invariantReferenceFloat(img, p);
	EXPECT_TRUE(std::isfinite(f.at<float>(0, 0)));
	auto q = p;
	q.order = ChannelOrder::RGB;
	const cv::Mat g = invariantReferenceFloat(img, q);
	EXPECT_GT(std::abs(f.at<float>(0, 1) - g.at<float>(0, 1)), 0.1);
}

TEST(InvariantTransformTest, RejectsGreyInput)
{
	cv::Mat grey(10, 10, CV_8UC1, cv::Scalar(100)), out;
	EXPECT_THROW(InvariantTransform().apply(grey, out), std::invalid_argument);
}

TEST(InvariantTransformTest, PairOnTwoThreadsEqualsSequential)
{
	cv::Mat l(100, 120, CV_8UC3), r(100, 120, CV_8UC3);
	cv::randu(l, 0, 255);
	cv::randu(r, 0, 255);
	InvariantTransform t;
	cv::Mat a, b, c, d;
	t.applyPair(l, r, a, b, true);
	t.applyPair(l, r, c, d, false);
	EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0);
	EXPECT_EQ(cv::norm(b, d, cv::NORM_INF), 0);
}

TEST(MonochromeTest, NeutralGreyStaysAndGreyCopies)
{
	cv::Mat img(4, 4, CV_8UC3, cv::Scalar(77, 77, 77)), out;
	toMonochrome(img, out, ChannelOrder::BGR);
	EXPECT_EQ(out.type(), CV_8UC1);
	EXPECT_EQ(out.at<uint8_t>(2, 2), 77);
	cv::Mat g(4, 4, CV_8UC1, cv::Scalar(9)), o2;
	toMonochrome(g, o2, ChannelOrder::RGB);
	EXPECT_EQ(o2.at<uint8_t>(0, 0), 9);
}
