/* Tests of the stereo VO on a ray-cast textured corridor with known poses:
 * accuracy on both channels, keyframe chain, and robustness to a blank frame. */
#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/sim/SyntheticCorridor.h>
#include <shadyloc/vo/ChannelOptions.h>
#include <shadyloc/vo/StereoVO.h>

#include "../support/Sequences.h"
#include "../support/TestSupport.h"

#include <mrpt/config/CConfigFileMemory.h>

#include <Eigen/Eigenvalues>

#include <cstdio>

using namespace shadyloc;

namespace
{
constexpr int kFrames = 50;	 // 5 m at 0.1 m per frame
constexpr double kSpeed = 0.1;

struct TSequence
{
	geometry::TStereoCalib calib;
	std::vector<cv::Mat> left, right;  // colour, BGR
	eval::Trajectory gt;  // left camera in the first frame
};

/** Read from the ctest fixture (tests/support/Sequences.h), or rendered once
 * per test binary (about a second). */
const TSequence& sequence()
{
	static const TSequence seq = [] {
		const auto& f = test::corridorSequence(kFrames, kSpeed);
		TSequence s;
		s.calib = f.calib;
		s.left = f.left;
		s.right = f.right;
		const Eigen::Isometry3d T0inv = f.T_world_left[0].inverse();
		for (int k = 0; k < kFrames; k++) s.gt.push_back({f.t[k], T0inv * f.T_world_left[k]});
		return s;
	}();
	return seq;
}

struct TVoRun
{
	eval::Trajectory est;
	std::vector<vo::TFrameResult> frames;
	std::vector<vo::TKeyframe> keyframes;
};

/** Runs the VO on the sequence in one channel; `blank` frames get a flat grey pair. */
TVoRun runVO(
	const std::string& ch, const std::vector<int>& blank = {}, const vo::TStereoVOOptions& opts = {})
{
	const auto& s = sequence();
	// Synthetic colours are linear already: no linearisation.
	const auto conv = filters::defaultChannel(ch);
	vo::StereoVO vo(opts);
	vo.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	TVoRun run;
	for (int k = 0; k < kFrames; k++)
	{
		cv::Mat l, r;
		conv.convert(s.left[k], l);
		conv.convert(s.right[k], r);
		if (std::find(blank.begin(), blank.end(), k) != blank.end())
		{
			l.setTo(128);
			r.setTo(128);
		}
		const auto res = vo.process(l, r, s.calib, s.gt[k].t);
		run.frames.push_back(res);
		run.est.push_back({res.timestamp, res.T_world_curr});
	}
	run.keyframes = vo.keyframes();
	return run;
}

void printRun(const char* name, const TVoRun& run, const eval::TTrajectoryErrors& e)
{
	size_t tracked = 0, inl = 0;
	for (const auto& f : run.frames)
	{
		tracked += f.tracked;
		inl += f.inliers;
	}
	std::printf(
		"[vo-synthetic] %-9s: %zu keyframes, mean tracked %.0f, mean inliers %.0f, ATE %.4f m, "
		"KITTI-style trans %.3f %%, rot %.4f deg/m, final drift %.4f m over %.2f m\n",
		name, run.keyframes.size(), double(tracked) / run.frames.size(), double(inl) / run.frames.size(),
		e.ate_rmse, e.kitti_trans_pct, e.kitti_rot_deg_per_m,
		(run.est.back().T.translation() - sequence().gt.back().T.translation()).norm(), e.path_length);
}
}  // namespace

TEST(VOSynthetic, MonoTranslationalErrorBelowOnePercent)
{
	const TVoRun run = runVO("mono");
	for (const auto& f : run.frames)
		EXPECT_TRUE(vo::isTracked(f.status)) << "frame " << f.frame << ": " << vo::toString(f.status);
	const auto e = eval::computeErrors(sequence().gt, run.est);
	printRun("mono", run, e);
	// Goal from the task: < 1 % translational error (KITTI-style, lengths
	// scaled to this 5 m run). Ideal images with 1 grey-level noise leave
	// sub-pixel errors only; 1 % of 5 m is 5 cm.
	EXPECT_LT(e.kitti_trans_pct, 1.0);
	EXPECT_LT(e.ate_rmse, 0.05);
	// Keyframes on overlap loss (the walls stream past the 65 deg field of
	// view; 13 over 50 frames measured) or every 1 m: some, but not every frame.
	EXPECT_GE(run.keyframes.size(), 3u);
	EXPECT_LE(run.keyframes.size(), 25u);
	// The chain of relative transforms reproduces the keyframe poses.
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	for (const auto& kf : run.keyframes)
	{
		T = T * kf.T_prevkf_kf;
		EXPECT_LT((T.matrix() - kf.T_world_kf.matrix()).norm(), 1e-9);
		EXPECT_FALSE(kf.chain_break);
		EXPECT_FALSE(kf.meas.empty());
		if (kf.id > 0)
		{
			// A positive definite covariance with a translation sigma in a
			// plausible range (0.1 mm .. 10 cm for a 1 m stereo step).
			Eigen::SelfAdjointEigenSolver<geometry::Matrix6d> es(kf.cov);
			EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
			const double st = std::sqrt(kf.cov.topLeftCorner<3, 3>().trace());
			EXPECT_GT(st, 1e-4);
			EXPECT_LT(st, 0.1);
		}
	}
}

TEST(VOSynthetic, InvariantTranslationalErrorBelowThreePercent)
{
	const TVoRun run = runVO("invariant");
	int tracked = 0;
	for (const auto& f : run.frames) tracked += vo::isTracked(f.status);
	const auto e = eval::computeErrors(sequence().gt, run.est);
	printRun("invariant", run, e);
	EXPECT_EQ(tracked, kFrames);
	// Goal from the task for the noisier invariant channel: < 3 %.
	EXPECT_LT(e.kitti_trans_pct, 3.0);
}

TEST(VOSynthetic, BlankFrameIsReportedAndTrackingResumes)
{
	// Frame 20 blank (lens cap, dropped exposure): no features at all.
	const TVoRun run = runVO("mono", {20});
	const auto& f20 = run.frames[20];
	EXPECT_EQ(f20.status, vo::FrameStatus::FewFeatures);
	EXPECT_EQ(f20.stereo, 0u);
	// Not a wild pose: the constant-velocity prediction, within a few cm of
	// the truth (the path's acceleration over one 0.1 m step is small).
	const auto& gt = sequence().gt;
	EXPECT_LT((f20.T_world_curr.translation() - gt[20].T.translation()).norm(), 0.05);
	// The next frame is tracked again, and the run as a whole stays accurate.
	EXPECT_TRUE(vo::isTracked(run.frames[21].status)) << vo::toString(run.frames[21].status);
	for (int k = 21; k < kFrames; k++) EXPECT_TRUE(vo::isTracked(run.frames[k].status)) << k;
	eval::Trajectory est;  // evaluate on the tracked frames
	for (const auto& f : run.frames)
		if (vo::isTracked(f.status)) est.push_back({f.timestamp, f.T_world_curr});
	const auto e = eval::computeErrors(gt, est);
	EXPECT_LT(e.kitti_trans_pct, 1.0);
}

TEST(VOSynthetic, LongBlankGapIsBridgedByPrediction)
{
	// Five blank frames in a row: each is reported; the next good frame is
	// matched to the old keyframe in the wide window around the
	// constant-velocity prediction.
	const TVoRun run = runVO("mono", {10, 11, 12, 13, 14});
	for (int k = 10; k <= 14; k++) EXPECT_EQ(run.frames[k].status, vo::FrameStatus::FewFeatures) << k;
	for (int k = 15; k < kFrames; k++) EXPECT_TRUE(vo::isTracked(run.frames[k].status)) << k;
	// No wild pose anywhere: predictions over 0.5 m of travel stay within a
	// few cm (the path's lateral sway changes velocity slowly), tracked frames within 5 cm.
	const auto& gt = sequence().gt;
	for (int k = 0; k < kFrames; k++)
		EXPECT_LT((run.frames[k].T_world_curr.translation() - gt[k].T.translation()).norm(), 0.1)
			<< "frame " << k << " (" << vo::toString(run.frames[k].status) << ")";
}

TEST(VOSynthetic, SceneChangeReinitialisesAChainSegment)
{
	// From frame 20 on the walls carry a different texture (another seed):
	// nothing matches the keyframe any more. The VO reports the frames it
	// cannot track, then starts a new keyframe (chain break) at the predicted
	// pose and tracks on from it.
	const auto& s = sequence();
	sim::TCorridorOptions o;
	o.seed = 2;
	const sim::SyntheticCorridor other(o);
	const auto conv = filters::defaultChannel("mono");
	vo::StereoVO vo;
	vo.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	std::vector<vo::TFrameResult> res;
	const Eigen::Isometry3d T0 = sim::SyntheticCorridor::examplePose(0, kSpeed);
	for (int k = 0; k < 30; k++)
	{
		cv::Mat cl = s.left[k], cr = s.right[k], l, r;
		// Fresh images: rendering into cl/cr would overwrite the shared
		// sequence() frames (cv::Mat copies share pixels) and corrupt every
		// later test in the same process (it made NearLandmarkPreference fail
		// after this test in one binary run).
		if (k >= 20)
		{
			cl = cv::Mat();
			cr = cv::Mat();
			other.render(T0 * s.gt[k].T, cl, cr, k);
		}
		conv.convert(cl, l);
		conv.convert(cr, r);
		res.push_back(vo.process(l, r, s.calib, s.gt[k].t));
	}
	const int maxLost = vo.options().max_lost_frames;	// 3
	for (int k = 20; k < 20 + maxLost; k++) EXPECT_FALSE(vo::isTracked(res[k].status)) << k << ": " << vo::toString(res[k].status);
	EXPECT_EQ(res[20 + maxLost].status, vo::FrameStatus::Reinit);
	EXPECT_TRUE(res[20 + maxLost].keyframe);
	const auto& kfs = vo.keyframes();
	ASSERT_FALSE(kfs.empty());
	int breaks = 0;
	for (const auto& kf : kfs)
		if (kf.chain_break)
		{
			breaks++;
			EXPECT_EQ(kf.frame, static_cast<size_t>(20 + maxLost));
			EXPECT_GT(kf.cov(0, 0), 1.0);  // a prediction, not a measurement
		}
	EXPECT_EQ(breaks, 1);
	for (int k = 21 + maxLost; k < 30; k++) EXPECT_EQ(res[k].status, vo::FrameStatus::Ok) << k;
	// Bridged by constant velocity over 4 frames: within 10 cm of the truth.
	for (int k = 0; k < 30; k++)
		EXPECT_LT((res[k].T_world_curr.translation() - s.gt[k].T.translation()).norm(), 0.1) << k;
}

TEST(VOSynthetic, MotionPriorReplacesConstantVelocity)
{
	// The hook the combined system uses (the baseline VO predicting for the
	// invariant pipeline): with a tight 4 px window and no motion model, the
	// identity prediction misses most landmarks (near wall points move tens
	// of px per 0.3 m step); given the true motion as the prior, every frame tracks.
	const auto& s = sequence();
	const auto conv = filters::defaultChannel("invariant");
	vo::TStereoVOOptions o;
	o.constant_velocity = false;
	o.search_radius_px = o.search_radius_lost_px = 4;
	vo::StereoVO withPrior(o), without(o);
	withPrior.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	without.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	int lostWith = 0, lostWithout = 0;
	size_t trackedWith = 0, trackedWithout = 0;
	// Every third frame: 0.3 m steps.
	for (int k = 0; k < kFrames; k += 3)
	{
		cv::Mat l, r;
		conv.convert(s.left[k], l);
		conv.convert(s.right[k], r);
		const Eigen::Isometry3d prior = k > 0 ? s.gt[k - 3].T.inverse() * s.gt[k].T : Eigen::Isometry3d::Identity();
		const auto rp = withPrior.process(l, r, s.calib, s.gt[k].t, &prior);
		const auto rw = without.process(l, r, s.calib, s.gt[k].t);
		lostWith += !vo::isTracked(rp.status);
		lostWithout += !vo::isTracked(rw.status);
		trackedWith += rp.tracked;
		trackedWithout += rw.tracked;
	}
	std::printf(
		"[vo-prior] 4 px window: with prior %d untracked, %zu matches; identity prediction %d "
		"untracked, %zu matches\n",
		lostWith, trackedWith, lostWithout, trackedWithout);
	EXPECT_EQ(lostWith, 0);
	// Without the prior, fewer landmarks fall inside their window: at least
	// half as many matches over the run, or lost frames.
	EXPECT_TRUE(lostWithout > 0 || trackedWithout < 0.5 * trackedWith);
}

TEST(VOSynthetic, LongerRunAtBumblebeeResolution)
{
	// 20 m at 512x384 (f = 400 px, b = 0.12 m: the paper's Bumblebee2), 0.2 m
	// per frame, both channels. Drift must stay under the goals over dozens
	// of keyframes (about 0.1 % measured; the bounds are the task's goals).
	sim::TCorridorOptions co;
	co.width = 512;
	co.height = 384;
	co.fx = 400;
	co.baseline = 0.12;
	co.length = 100;
	const sim::SyntheticCorridor corridor(co);
	const auto cm = filters::defaultChannel("mono"), ci = filters::defaultChannel("invariant");
	vo::StereoVO vm, vi;
	vm.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	vi.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	eval::Trajectory gt, em, ei;
	const Eigen::Isometry3d T0inv = sim::SyntheticCorridor::examplePose(0, 0.2).inverse();
	int untracked = 0;
	for (int k = 0; k < 100; k++)
	{
		const Eigen::Isometry3d T = sim::SyntheticCorridor::examplePose(k, 0.2);
		cv::Mat l, r, a, b;
		corridor.render(T, l, r, static_cast<uint32_t>(k));
		cm.convert(l, a);
		cm.convert(r, b);
		const auto rm = vm.process(a, b, corridor.calib(), 0.1 * k);
		ci.convert(l, a);
		ci.convert(r, b);
		const auto ri = vi.process(a, b, corridor.calib(), 0.1 * k);
		untracked += !vo::isTracked(rm.status) + !vo::isTracked(ri.status);
		gt.push_back({0.1 * k, T0inv * T});
		em.push_back({0.1 * k, rm.T_world_curr});
		ei.push_back({0.1 * k, ri.T_world_curr});
	}
	const auto e1 = eval::computeErrors(gt, em), e2 = eval::computeErrors(gt, ei);
	std::printf(
		"[vo-long] %.1f m at 512x384: mono %zu keyframes, ATE %.4f m, KITTI-style %.3f %% %.4f deg/m | "
		"invariant %zu keyframes, ATE %.4f m, %.3f %% %.4f deg/m\n",
		e1.path_length, vm.keyframes().size(), e1.ate_rmse, e1.kitti_trans_pct, e1.kitti_rot_deg_per_m,
		vi.keyframes().size(), e2.ate_rmse, e2.kitti_trans_pct, e2.kitti_rot_deg_per_m);
	EXPECT_EQ(untracked, 0);
	EXPECT_GT(vm.keyframes().size(), 10u);
	EXPECT_LT(e1.kitti_trans_pct, 1.0);
	EXPECT_LT(e2.kitti_trans_pct, 3.0);
}

TEST(VOSynthetic, NearLandmarkPreferenceTracksAndKeepsAccuracy)
{
	// near_min_disparity = 5 px: with f = 250 px and b = 0.2 m only landmarks
	// nearer than 10 m enter the solve when >= 40 such matches exist (the
	// corridor's walls give ~200 matches per frame, most of them near).
	vo::TStereoVOOptions o;
	o.near_min_disparity = 5;
	o.near_min_matches = 40;
	const TVoRun run = runVO("mono", {}, o);
	const TVoRun all = runVO("mono");
	size_t used = 0, usedAll = 0;
	for (size_t k = 0; k < run.frames.size(); k++)
	{
		EXPECT_TRUE(vo::isTracked(run.frames[k].status)) << "frame " << k;
		used += run.frames[k].tracked;
		usedAll += all.frames[k].tracked;
	}
	// The option really removed far matches from the solve ...
	EXPECT_LT(used, usedAll);
	// ... and the result still meets the mono goal (see MonoTranslationalErrorBelowOnePercent).
	const auto e = eval::computeErrors(sequence().gt, run.est);
	printRun("mono near", run, e);
	EXPECT_LT(e.kitti_trans_pct, 1.0);
	EXPECT_LT(e.ate_rmse, 0.05);
}

TEST(VOSynthetic, PerChannelVOOptionsOverrideTheBaseSection)
{
	mrpt::config::CConfigFileMemory cfg(
		"[vo]\nnear_min_disparity_px = 0\nmax_hamming = 70\n[vo.mono]\nnear_min_disparity_px = 3\n");
	const auto m = vo::voOptionsFor(cfg, "mono");
	const auto i = vo::voOptionsFor(cfg, "invariant");
	EXPECT_EQ(m.near_min_disparity, 3.0);
	EXPECT_EQ(i.near_min_disparity, 0.0);
	EXPECT_EQ(m.max_hamming, 70);  // base keys reach both channels
	EXPECT_EQ(i.max_hamming, 70);
	// A bad value names the section and the option.
	mrpt::config::CConfigFileMemory bad("[vo]\n[vo.mono]\nnear_min_matches = 2\n");
	try
	{
		vo::voOptionsFor(bad, "mono");
		ADD_FAILURE() << "near_min_matches < min_matches accepted";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[vo.mono]"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("near_min_matches"), std::string::npos) << e.what();
	}
}
