/* Stereo measurements against the shadow simulator's rendered depth: the
 * disparity of near landmarks must be unbiased (the mono VO's scale rests on
 * them), and the known high bias of far landmarks must not grow
 * (docs/vo.md, "The scale bias: far landmarks' disparity is biased high"). */
#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/sim/StereoSimulator.h>
#include <shadyloc/sim/SimOptions.h>
#include <shadyloc/vo/ChannelOptions.h>

#include "../support/TestSupport.h"

#include <mrpt/config/CConfigFile.h>

#include <cmath>
#include <cstdio>

using namespace shadyloc;

TEST(FeaturesSimDisparity, NearDisparityUnbiasedAgainstRenderedDepth)
{
	auto o = sim::TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	o.traversals = {o.traversal("noon")};
	sim::StereoSimulator s(o);
	s.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	mrpt::config::CConfigFile cfg(std::string(SHADYLOC_SOURCE_DIR) + "/config/vo_sim.ini");
	const auto conv = filters::channelFromConfig(cfg, "mono", "config/vo_sim.ini");
	const features::StereoFeatureExtractor ex(vo::featureOptionsFor(cfg, "mono"));
	// Sums over measurements within 1 px of the truth, near (D >= 4 px, Z < 12 m) and far (D < 4 px).
	double sumNear = 0, sumSqNear = 0, sumFar = 0;
	int nNear = 0, nFar = 0, nAll = 0, nGross = 0;
	for (int i = 0; i < 6; i++)
	{
		sim::TRenderAux aux;
		const auto f = s.renderFrame(i, &aux);
		const auto calib = geometry::TStereoCalib::FromObservation(*s.makeObservation(f));
		cv::Mat l, r;
		conv.convert(f.left, l);
		conv.convert(f.right, r);
		features::TStereoFrame fr;
		ex.process(l, r, calib, fr);
		for (const auto& m : fr.meas)
		{
			// Rendered depth along the optical axis at the left corner's pixel (0: sky).
			const float z = aux.depth.at<float>(static_cast<int>(m.v), static_cast<int>(m.uL));
			if (!(z > 0)) continue;
			const double Dgt = calib.fx * calib.baseline / z;
			const double e = calib.disparity(m.uL, m.uR) - Dgt;
			nAll++;
			if (std::abs(e) > 1)
			{
				nGross++;
				continue;
			}
			if (Dgt >= 4)
			{
				sumNear += e;
				sumSqNear += e * e;
				nNear++;
			}
			else
			{
				sumFar += e;
				nFar++;
			}
		}
	}
	ASSERT_GT(nNear, 500);	// measured 1883 near, 1472 far over 6 frames
	ASSERT_GT(nFar, 200);
	const double biasNear = sumNear / nNear, rmsNear = std::sqrt(sumSqNear / nNear), biasFar = sumFar / nFar;
	std::printf(
		"[ sim disparity ] %d measurements, %.1f %% off by > 1 px; near (D >= 4 px): %d, bias %+.3f px, "
		"rms %.3f px; far: %d, bias %+.3f px\n",
		nAll, 100.0 * nGross / nAll, nNear, biasNear, rmsNear, nFar, biasFar);
	// Measured (Gauss-Newton sub-pixel uR): near bias +0.001 px, rms 0.146 px
	// (parabola only: -0.002, 0.155); 2.6 % gross errors (nearly all at depth
	// discontinuities: the corner pixel sees the background); far bias
	// +0.12 px, mostly corners whose pixel is background while the foreground
	// dominates the patch (docs/vo.md). A 0.05 px near bias would be a 0.5 % scale error at
	// D = 10 px, half the mono goal; the far bound leaves ~2x room over the
	// measured value so that it catches a regression, not the known bias.
	EXPECT_LT(std::abs(biasNear), 0.05);
	EXPECT_LT(rmsNear, 0.3);
	EXPECT_LT(double(nGross) / nAll, 0.06);
	EXPECT_LT(biasFar, 0.25);
}
