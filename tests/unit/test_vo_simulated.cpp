/* Stereo VO on a short sequence rendered by the shadow simulator (the
 * realistic outdoor data: trees, buildings, shadows, sensor noise, auto
 * exposure, ~0.8 m per frame): KITTI-style drift of both channels with the
 * configuration made for the simulator's camera (config/vo_sim.ini). */
#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/sim/StereoSimulator.h>
#include <shadyloc/sim/SimOptions.h>
#include <shadyloc/vo/ChannelOptions.h>
#include <shadyloc/vo/StereoVO.h>

#include "../support/Sequences.h"
#include "../support/TestSupport.h"

#include <mrpt/config/CConfigFile.h>

#include <cstdio>

using namespace shadyloc;

namespace
{
struct TSimSequence
{
	geometry::TStereoCalib calib;
	std::vector<cv::Mat> left, right;  // colour, BGR, linear
	eval::Trajectory gt;  // left camera in the world
};

/** The first frames of one traversal at the simulator's default 512x384, from
 * the ctest fixture (tests/support/Sequences.h) or rendered here. */
TSimSequence simTraversal(const std::string& traversal)
{
	const auto& f = test::simSequence(traversal);
	TSimSequence seq;
	seq.calib = f.calib;
	seq.left = f.left;
	seq.right = f.right;
	for (size_t i = 0; i < f.left.size(); i++) seq.gt.push_back({f.t[i], f.T_world_left[i]});
	return seq;
}

eval::TTrajectoryErrors runSimVO(const TSimSequence& seq, const std::string& ch, size_t* tracked)
{
	mrpt::config::CConfigFile cfg(std::string(SHADYLOC_SOURCE_DIR) + "/config/vo_sim.ini");
	const auto conv = filters::channelFromConfig(cfg, ch, "config/vo_sim.ini");
	vo::StereoVO v(vo::voOptionsFor(cfg, ch), vo::featureOptionsFor(cfg, ch));
	v.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	eval::Trajectory est;
	*tracked = 0;
	for (size_t i = 0; i < seq.left.size(); i++)
	{
		cv::Mat l8, r8;
		conv.convert(seq.left[i], l8);
		conv.convert(seq.right[i], r8);
		const auto r = v.process(l8, r8, seq.calib, seq.gt[i].t);
		*tracked += vo::isTracked(r.status);
		est.push_back({seq.gt[i].t, r.T_world_curr});
	}
	return eval::computeErrors(seq.gt, est);
}
}  // namespace

// 30 frames (~20 m) of the noon and overcast traversals at the simulator's
// default 512x384 (~4 s in Release; at 256x192 the disparities halve and the
// drift roughly triples, so half size would test the resolution, not the VO).
// On the 60-frame default dataset the same configuration measures mono
// 0.21-0.43 % and invariant 0.96-1.65 % (docs/vo.md, "Simulator sequences").
// Both bounds are the goals themselves (mono 1 %, invariant 3 %). Measured on
// these 20 m runs: noon 0.27 % / 2.10 %, overcast 0.39 % / 1.56 %; a 20 m run
// averages fewer, shorter segments than the full traversals, so one poor step
// weighs more. The runs are deterministic (seeded renderer and RANSAC, tested
// by VODeterminism), so the bounds fail on a regression, not on noise: the
// solver before the two-view adjustment and the prediction hypothesis gave
// invariant 4.0-4.9 % and, without the prediction hypothesis, 7-15 %.
class VOSimulated : public ::testing::TestWithParam<const char*>
{
};

TEST_P(VOSimulated, ShortTraversalDriftBothChannels)
{
	const std::string trav = GetParam();
	const auto seq = simTraversal(trav);
	size_t trMono = 0, trInv = 0;
	const auto em = runSimVO(seq, "mono", &trMono);
	const auto ei = runSimVO(seq, "invariant", &trInv);
	std::printf(
		"[ sim VO ] %s 512x384, %.1f m: mono %.2f %% %.4f deg/m (%zu tracked), invariant %.2f %% "
		"%.4f deg/m (%zu tracked)\n",
		trav.c_str(), em.path_length, em.kitti_trans_pct, em.kitti_rot_deg_per_m, trMono, ei.kitti_trans_pct,
		ei.kitti_rot_deg_per_m, trInv);
	EXPECT_GT(em.path_length, 15.0) << trav;  // the simulator really moved ~0.8 m per frame
	// Mono: every frame tracked, drift below the 1 % goal.
	EXPECT_EQ(trMono, seq.left.size()) << trav;
	EXPECT_LT(em.kitti_trans_pct, 1.0) << trav;
	EXPECT_LT(em.kitti_rot_deg_per_m, 0.1) << trav;
	// Invariant: lower contrast, noisier; at most a couple of untracked frames, drift < 3 %.
	EXPECT_GE(trInv + 2, seq.left.size()) << trav;
	EXPECT_LT(ei.kitti_trans_pct, 3.0) << trav;
	EXPECT_LT(ei.kitti_rot_deg_per_m, 0.2) << trav;
}

INSTANTIATE_TEST_SUITE_P(
	Traversals, VOSimulated, ::testing::Values("noon", "overcast"),
	[](const ::testing::TestParamInfo<const char*>& i) { return std::string(i.param); });
