/* Sub-pixel estimators against images shifted by known fractions of a pixel:
 * the parabola through three integer-shift correlation scores is biased
 * towards integer shifts ("pixel locking", Shimizu & Okutomi, ICCV 2001);
 * the Gauss-Newton refinements (refineRowShift, refinePatch2D) must not be. */
#include <shadyloc/features/StereoFeatures.h>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

using namespace shadyloc;

namespace
{
constexpr int kUp = 8;	// shifts in steps of 1/kUp px

/** A band-limited random texture at kUp x the output resolution: shifting its
 * box-filtered (INTER_AREA) crops by k fine pixels gives images that differ by
 * exactly k/kUp px, every one sampled the same way (no interpolation of one eye). */
cv::Mat fineTexture(int W, int H)
{
	cv::Mat t(H, W, CV_8U);
	cv::RNG rng(20260);
	rng.fill(t, cv::RNG::UNIFORM, 0, 256);
	cv::GaussianBlur(t, t, cv::Size(), 0.7);  // about a FAST corner's scale
	cv::normalize(t, t, 20, 235, cv::NORM_MINMAX);
	cv::Mat fine;
	cv::resize(t, fine, cv::Size(), kUp, kUp, cv::INTER_CUBIC);
	return fine;
}

/** Box-filtered crop of the fine texture starting k fine pixels right and kv down. */
cv::Mat shifted(const cv::Mat& fine, int W, int H, int k, int kv = 0)
{
	cv::Mat out;
	cv::resize(fine(cv::Rect(k, kv, W * kUp, H * kUp)), out, cv::Size(W, H), 0, 0, cv::INTER_AREA);
	return out;
}

/** Largest |mean disparity error| over shifts 1..2 px in 1/8 px steps, and the rms. */
void stereoLocking(int subpixelIterations, double& worstMean, double& rms)
{
	const int W = 200, H = 150;
	const cv::Mat fine = fineTexture(W + 4, H + 1);
	features::TStereoFeatureOptions o;
	o.min_disparity = 0.3;
	o.max_disparity = 8;
	o.subpixel_iterations = subpixelIterations;
	const features::StereoFeatureExtractor ex(o);
	geometry::TStereoCalib calib;
	calib.fx = calib.fy = 200;
	calib.cx = calib.cxR = W / 2.0;
	calib.cy = H / 2.0;
	calib.baseline = 0.1;
	const cv::Mat L = shifted(fine, W, H, 0);
	worstMean = 0;
	double sse = 0;
	int nAll = 0;
	for (int k = kUp; k <= 2 * kUp; k++)
	{
		const double d = double(k) / kUp;  // R(x) = L(x + d): uR = uL - d
		features::TStereoFrame fr;
		ex.process(L, shifted(fine, W, H, k), calib, fr);
		double se = 0;
		int n = 0;
		for (const auto& m : fr.meas)
		{
			const double e = calib.disparity(m.uL, m.uR) - d;
			if (std::abs(e) > 0.5) continue;  // a wrong corner, not sub-pixel error
			se += e;
			sse += e * e;
			n++;
		}
		ASSERT_GT(n, 50) << "shift " << d;
		if (std::getenv("SUBPIX_VERBOSE")) std::printf("  d %.3f mean %+.4f n %d\n", d, se / n, n);
		worstMean = std::max(worstMean, std::abs(se / n));
		nAll += n;
	}
	rms = std::sqrt(sse / nAll);
}
}  // namespace

TEST(FeaturesSubpixel, StereoDisparityHasNoPixelLocking)
{
	double worstPar, rmsPar, worstGN, rmsGN;
	stereoLocking(0, worstPar, rmsPar);
	stereoLocking(5, worstGN, rmsGN);
	std::printf(
		"[subpixel] stereo, shifts 1..2 px: parabola worst mean error %.3f px, rms %.3f px | "
		"Gauss-Newton %.3f px, rms %.3f px\n",
		worstPar, rmsPar, worstGN, rmsGN);
	// The parabola's bias is systematic (the same sign for every corner at a
	// given fraction), so its worst mean is far above the noise of a mean over
	// hundreds of corners; the test must see it, else it could not fail.
	EXPECT_GT(worstPar, 0.03);
	// Measured: parabola 0.048 px worst mean, rms 0.049 px; Gauss-Newton
	// 0.021 px, rms 0.014 px. What is left is the cubic interpolation's own
	// phase error at fractional shifts (it pushes slightly away from integers).
	EXPECT_LT(worstGN, 0.03);
	EXPECT_LT(worstGN, 0.6 * worstPar);
	EXPECT_LT(rmsGN, 0.5 * rmsPar);
}

TEST(FeaturesSubpixel, PatchRefinement2DHasNoPixelLocking)
{
	const int W = 120, H = 120;
	const cv::Mat fine = fineTexture(W + 2, H + 2);
	const cv::Mat A = shifted(fine, W, H, 0, 0);
	constexpr int S = features::kPatchSize, h = S / 2;
	double worstPar = 0, worstGN = 0;
	int failed = 0, total = 0;
	for (int kx = 0; kx < kUp; kx++)
		for (int ky = 0; ky < kUp; ky += 3)
		{
			// B(x, y) = A(x + dx, y + dy): a template at (x, y) in A sits at (x - dx, y - dy) in B.
			const double dx = double(kx) / kUp, dy = double(ky) / kUp;
			const cv::Mat B = shifted(fine, W, H, kx, ky);
			double sumPx = 0, sumPy = 0, sumGx = 0, sumGy = 0;
			int n = 0;
			for (int y = 15; y < H - 15; y += 6)
				for (int x = 15; x < W - 15; x += 6)
				{
					std::array<uint8_t, S * S> tmpl;
					for (int r = 0; r < S; r++)
						for (int c = 0; c < S; c++) tmpl[r * S + c] = A.at<uint8_t>(y - h + r, x - h + c);
					// Integer start nearest the truth, then the 2D parabola (as the VO does).
					const int xi = static_cast<int>(std::lround(x - dx)), yi = static_cast<int>(std::lround(y - dy));
					float cc[3][3];
					for (int j = -1; j <= 1; j++)
						for (int i = -1; i <= 1; i++) cc[j + 1][i + 1] = features::zncc(A, x, y, B, xi + i, yi + j, h);
					const float px = xi + features::parabolaPeak(cc[1][0], cc[1][1], cc[1][2]);
					const float py = yi + features::parabolaPeak(cc[0][1], cc[1][1], cc[2][1]);
					float gx, gy;
					total++;
					if (!features::refinePatch2D(tmpl.data(), S, B, px, py, 5, gx, gy))
					{
						failed++;
						continue;
					}
					sumPx += px - (x - dx);
					sumPy += py - (y - dy);
					sumGx += gx - (x - dx);
					sumGy += gy - (y - dy);
					n++;
				}
			ASSERT_GT(n, 100);
			worstPar = std::max({worstPar, std::abs(sumPx / n), std::abs(sumPy / n)});
			worstGN = std::max({worstGN, std::abs(sumGx / n), std::abs(sumGy / n)});
		}
	std::printf(
		"[subpixel] 2D patch, shifts 0..7/8 px: parabola worst mean error %.3f px | Gauss-Newton %.3f px "
		"(%d of %d refinements refused)\n",
		worstPar, worstGN, failed, total);
	// Measured: parabola 0.051 px, Gauss-Newton 0.023 px (see above).
	EXPECT_GT(worstPar, 0.03);	// the test sees locking
	EXPECT_LT(worstGN, 0.03);
	EXPECT_LT(worstGN, 0.6 * worstPar);
	EXPECT_LT(failed, total / 50);	// a clean shifted texture: almost every refinement converges
}
