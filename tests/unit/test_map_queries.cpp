/* Tests of the keyframe map's queries (nearest with heading, along the chain,
 * relative pose with covariance), the descriptor-parameter check, the
 * CMetricMap virtuals it refuses, landmark selection, and `shadyloc survey`
 * / `map-info` end to end on a synthetic stereo run. */
#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/survey/SurveyBuilder.h>
#include <shadyloc/sim/SyntheticCorridor.h>

#include "../support/TestSupport.h"
#include "test_map_support.h"

#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/poses/CPose3D.h>

#include <opencv2/imgproc.hpp>

#include <fstream>
#include <random>
#include <regex>

using namespace shadyloc;

namespace
{
Eigen::Isometry3d mapPoseAt(double x, double z, double yawDeg)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = Eigen::AngleAxisd(yawDeg * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
	T.translation() = Eigen::Vector3d(x, 0, z);
	return T;
}
}  // namespace

TEST(MapQueries, NearestKeyframesRespectHeading)
{
	auto m = test::makeSyntheticMap(4, 5, 0);
	// Rebuild: an out-and-back road, the return leg 0.5 m to the side, facing back.
	auto r = CKeyframeMap::Create();
	r->setup(m->calibration(), 512, 384, m->channels());
	const uint16_t run = r->addRun("outback");
	std::vector<Eigen::Isometry3d> poses;
	for (int i = 0; i <= 20; i++) poses.push_back(mapPoseAt(0, 2.0 * i, 0));
	for (int i = 20; i >= 0; i--) poses.push_back(mapPoseAt(0.5, 2.0 * i + 1, 180));
	for (size_t i = 0; i < poses.size(); i++)
	{
		map::TMapKeyframe k;
		k.run = run;
		k.T_map_kf = poses[i];
		k.T_prev_kf = i ? poses[i - 1].inverse() * poses[i] : Eigen::Isometry3d::Identity();
		k.channels.resize(2);
		r->appendKeyframe(k);
	}
	map::TNearestQuery q;
	q.max_distance_m = 3;
	q.max_angle_deg = 30;
	// Driving forward at z = 10.2: keyframes at z = 10 (id 5), 12, 8; never the return leg.
	auto hits = r->nearestKeyframes(mapPoseAt(0.1, 10.2, 5), q);
	ASSERT_FALSE(hits.empty());
	EXPECT_EQ(hits[0].id, 5u);
	for (const auto& h : hits) EXPECT_LE(h.id, 20u) << "a keyframe facing the other way was returned";
	// Driving back at the same place: only the return leg (ids 21..41), z = 11 is id 41 - 5 = 36.
	hits = r->nearestKeyframes(mapPoseAt(0.4, 10.9, 178), q);
	ASSERT_FALSE(hits.empty());
	EXPECT_EQ(hits[0].id, 36u);
	for (const auto& h : hits) EXPECT_GT(h.id, 20u);
	// Brute force agrees over many random queries (the index misses nothing).
	std::mt19937 rng(3);
	std::uniform_real_distribution<double> U(-5, 45), Y(-180, 180);
	for (int t = 0; t < 300; t++)
	{
		const auto T = mapPoseAt(U(rng) / 10, U(rng), Y(rng));
		q.max_results = 100;
		const auto got = r->nearestKeyframes(T, q);
		size_t expected = 0;
		for (const auto& k : r->keyframes())
		{
			const double d = (k.T_map_kf.translation() - T.translation()).norm();
			const double c = T.linear().col(2).dot(k.T_map_kf.linear().col(2));
			expected += d <= q.max_distance_m && c >= std::cos(q.max_angle_deg * M_PI / 180);
		}
		EXPECT_EQ(got.size(), expected);
	}
}

TEST(MapQueries, AlongTheChainStopsAtBreaks)
{
	const auto m = test::makeSyntheticMap(24, 5, 15);
	// ~2.1 m spacing: 5 m ahead of keyframe 3 reaches 5 (not 6); 3 m behind reaches 2.
	const auto ids = m->keyframesAlongChain(3, 3.0, 5.0);
	ASSERT_FALSE(ids.empty());
	EXPECT_EQ(ids.front(), 2u);
	EXPECT_EQ(ids.back(), 5u);
	// Keyframe 14 is the last of segment 0: nothing ahead of it.
	EXPECT_EQ(m->keyframesAlongChain(14, 0, 100).back(), 14u);
	EXPECT_EQ(m->keyframesAlongChain(16, 100, 0).front(), 15u);
	EXPECT_THROW(m->keyframesAlongChain(99, 1, 1), std::out_of_range);
}

TEST(MapQueries, RelativePoseComposesAndPropagates)
{
	const auto m = test::makeSyntheticMap(24, 5, 15);
	const auto r = m->relativePose(2, 9);
	const Eigen::Isometry3d expect = m->keyframe(2).T_map_kf.inverse() * m->keyframe(9).T_map_kf;
	EXPECT_TRUE(r.T_a_b.isApprox(expect, 1e-9));
	// Covariance grows along the chain and inverts consistently.
	const auto r1 = m->relativePose(2, 3), r7 = m->relativePose(2, 9);
	EXPECT_GT(r7.cov.trace(), r1.cov.trace());
	EXPECT_NEAR(r7.chain_length_m, m->chainDistance(9) - m->chainDistance(2), 1e-12);
	const auto back = m->relativePose(9, 2);
	EXPECT_TRUE(back.T_a_b.isApprox(expect.inverse(), 1e-9));
	EXPECT_TRUE(back.cov.isApprox(geometry::invertCovariance(r.T_a_b, r.cov), 1e-9));
	// Across the break: refused, naming both keyframes.
	try
	{
		m->relativePose(10, 20);
		FAIL() << "chained across a VO break";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("10"), std::string::npos);
		EXPECT_NE(std::string(e.what()).find("20"), std::string::npos);
	}
}

TEST(MapQueries, MeasurementsByChannelAndDescriptorCheck)
{
	const auto m = test::makeSyntheticMap();
	EXPECT_EQ(m->measurements(4, "mono").size(), 40u);
	EXPECT_EQ(&m->measurements(4, "invariant"), &m->keyframe(4).channels[1]);
	EXPECT_THROW(m->measurements(4, "infrared"), std::out_of_range);
	auto live = m->channels()[1];
	EXPECT_NO_THROW(m->checkCompatible(live));
	// A live run whose invariant filter maps to 8 bits differently and whose
	// BRIEF pattern differs, recorded as a survey records its channels.
	CFilterInvariant liveFilter;
	auto ip = image::InvariantParams::FromWavelengths(470, 540, 620);
	ip.scale = 255;
	liveFilter.setParams(ip);
	features::TStereoFeatureOptions fo;
	fo.presmooth_sigma = live.presmooth_sigma;
	fo.brief_seed = live.brief_seed ^ 1;
	live = survey::channelParams("invariant", liveFilter, fo);
	try
	{
		m->checkCompatible(live);
		FAIL() << "other descriptor parameters accepted";
	}
	catch (const std::runtime_error& e)
	{
		const std::string w = e.what();
		EXPECT_NE(w.find("BRIEF pattern seed"), std::string::npos) << w;
		EXPECT_NE(w.find("filter option scale"), std::string::npos) << w;
		EXPECT_EQ(w.find("filter option alpha"), std::string::npos) << w;  // only what differs
		EXPECT_NE(w.find("scale=255"), std::string::npos) << w;
		EXPECT_NE(w.find("map 'invariant'"), std::string::npos) << w;  // both sets named
		EXPECT_NE(w.find("live 'invariant'"), std::string::npos) << w;
		EXPECT_NE(w.find("scale=128"), std::string::npos) << w;
	}
	// sigma_px is not descriptor-defining.
	live = m->channels()[0];
	live.sigma_px = 2;
	EXPECT_NO_THROW(m->checkCompatible(live));
}

TEST(MapQueries, DescriptorKindAndPyramidAreDescriptorDefining)
{
	// A map of FAST + BRIEF refuses live ORB and the other way round, naming
	// both kinds; between two ORB channels the pyramid counts, BRIEF's pattern
	// does not (and the other way round between two BRIEF channels).
	const auto brief = test::makeSyntheticMap(4, 3, 0), orb = test::makeSyntheticMap(4, 3, 0, test::kChannelDescriptor);
	ASSERT_EQ(brief->channels()[1].descriptor, features::DescriptorKind::Brief);
	ASSERT_EQ(orb->channels()[1].descriptor, features::DescriptorKind::Orb);
	const auto refused = [](const CKeyframeMap& m, const map::TChannelParams& live) -> std::string {
		try
		{
			m.checkCompatible(live);
		}
		catch (const std::runtime_error& e)
		{
			return e.what();
		}
		return "";
	};
	std::string w = refused(*brief, orb->channels()[1]);
	EXPECT_NE(w.find("descriptor: map brief, live orb"), std::string::npos) << w;
	EXPECT_NE(w.find("ORB 8 levels scale 1.2"), std::string::npos) << w;	// the live set, in full
	EXPECT_NE(w.find("BRIEF patch 32"), std::string::npos) << w;	// the map's
	w = refused(*orb, brief->channels()[1]);
	EXPECT_NE(w.find("descriptor: map orb, live brief"), std::string::npos) << w;
	auto live = orb->channels()[1];
	live.orb_levels = 4;
	w = refused(*orb, live);
	EXPECT_NE(w.find("ORB pyramid levels"), std::string::npos) << w;
	live = orb->channels()[1];
	live.orb_scale_factor = 1.5;
	w = refused(*orb, live);
	EXPECT_NE(w.find("ORB scale factor"), std::string::npos) << w;
	live = orb->channels()[1];
	live.brief_seed ^= 1;
	EXPECT_EQ(refused(*orb, live), "");
	live = brief->channels()[1];
	live.orb_levels = 3;
	EXPECT_EQ(refused(*brief, live), "");
}

TEST(MapQueries, MeaninglessMetricMapCallsThrowNamingTheClass)
{
	const auto m = test::makeSyntheticMap(4, 3, 0);
	auto named = [](const std::function<void()>& f) {
		try
		{
			f();
		}
		catch (const std::exception& e)
		{
			return std::string(e.what()).find("CKeyframeMap") != std::string::npos;
		}
		return false;
	};
	mrpt::obs::CObservationStereoImages obs;
	EXPECT_TRUE(named([&] { m->insertObservation(obs); }));
	EXPECT_TRUE(named([&] { m->computeObservationLikelihood(obs, mrpt::poses::CPose3D()); }));
	EXPECT_FALSE(m->canComputeObservationLikelihood(obs));
	EXPECT_TRUE(named([&] { m->squareDistanceToClosestCorrespondence(0, 0); }));
	EXPECT_TRUE(named([&] { m->compute3DMatchingRatio(m.get(), mrpt::poses::CPose3D(), {}); }));
	mrpt::tfest::TMatchingPairList c;
	mrpt::maps::TMatchingExtraResults x;
	EXPECT_TRUE(named([&] { m->determineMatching3D(m.get(), mrpt::poses::CPose3D(), c, {}, x); }));
	// The summary names what matters; the 3D view holds the path and triads.
	const std::string s = m->asString();
	EXPECT_NE(s.find("4 keyframes"), std::string::npos) << s;
	EXPECT_NE(s.find("'mono'"), std::string::npos) << s;
	EXPECT_NE(s.find("alpha="), std::string::npos) << s;
	EXPECT_NE(s.find("kB/keyframe"), std::string::npos) << s;
	mrpt::opengl::CSetOfObjects scene;
	m->options.draw_landmarks = true;
	m->getVisualizationInto(scene);
	EXPECT_GE(scene.size(), 1u + 1u + 2u);	// path, >= 1 triad, one cloud per channel
}

TEST(MapQueries, LandmarkSelectionSpreadsOverTheImage)
{
	std::vector<features::TStereoMeasurement> all;
	// 200 strong corners in the top-left bucket, 20 weak ones elsewhere.
	for (int i = 0; i < 200; i++)
	{
		features::TStereoMeasurement m;
		m.uL = 5 + i % 20;
		m.v = 5 + i / 20;
		m.response = 100 + i;
		all.push_back(m);
	}
	for (int i = 0; i < 20; i++)
	{
		features::TStereoMeasurement m;
		m.uL = 100 + 20 * i;
		m.v = 300;
		m.response = 15;
		all.push_back(m);
	}
	const auto kept = survey::selectLandmarks(all, 40, 8, 6, 512, 384);
	ASSERT_EQ(kept.size(), 40u);
	int weak = 0;
	for (const auto& m : kept) weak += m.response == 15;
	EXPECT_EQ(weak, 20) << "every bucket must give up its corners before a bucket gives a second";
	EXPECT_EQ(survey::selectLandmarks(all, 0, 8, 6, 512, 384).size(), all.size());
}

TEST(MapQueries, LandmarkSelectionByScoreKeepsTheSpreadAndTheFloor)
{
	// Two buckets (left and right half of a 2x1 grid), 10 corners each: the
	// strongest corners of each bucket score 0, the weakest score highest.
	std::vector<features::TStereoMeasurement> all;
	std::vector<int> score;
	for (int b = 0; b < 2; b++)
		for (int i = 0; i < 10; i++)
		{
			features::TStereoMeasurement m;
			m.uL = 10 + 300 * b + i;
			m.v = 100;
			m.response = 100 - i;  // i = 0 strongest
			all.push_back(m);
			score.push_back(i < 5 ? 0 : i);	 // the five weakest re-observed, the weakest most often
		}
	const auto idx = survey::selectLandmarkIndices(all, 4, 2, 1, 512, 384, &score);
	ASSERT_EQ(idx.size(), 4u);
	// Round robin over the buckets, best score first in each: 9, 19, 8, 18.
	EXPECT_EQ(idx, (std::vector<size_t>{9, 19, 8, 18}));
	// Without a score: the strongest corners.
	EXPECT_EQ(survey::selectLandmarkIndices(all, 4, 2, 1, 512, 384), (std::vector<size_t>{0, 10, 1, 11}));
	// A floor drops the never re-observed even when the budget has room (0 = no budget).
	const auto floor = survey::selectLandmarkIndices(all, 0, 2, 1, 512, 384, &score, 1);
	EXPECT_EQ(floor.size(), 10u);
	for (size_t i : floor) EXPECT_GE(score[i], 1) << i;
	const std::vector<int> wrong(3, 0);  // not one score per measurement
	EXPECT_THROW(survey::selectLandmarkIndices(all, 4, 2, 1, 512, 384, &wrong), std::invalid_argument);
}

TEST(MapQueries, ReobservationsFindStableLandmarksAndRejectMovedOnes)
{
	// A corridor keyframe re-observed by three frames 0.3, 0.6, 0.9 m ahead
	// at their true poses. Half of the keyframe's landmarks are kept as they
	// are; a quarter are moved (their measurement shifted 8 px sideways, as a
	// leaf that moved between the frames: the descriptor still finds the
	// corner, but the solve rejects it); a quarter get foreign descriptors
	// (nothing matches them). Only the first half can score.
	sim::SyntheticCorridor corridor;
	const auto calib = corridor.calib();
	features::StereoFeatureExtractor fx;
	auto grey = [](const cv::Mat& bgr) {
		cv::Mat g;
		cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
		return g;
	};
	auto frameAt = [&](const Eigen::Isometry3d& T, uint32_t seed) {
		cv::Mat l, r;
		corridor.render(T, l, r, seed);
		features::TStereoFrame f;
		fx.process(grey(l), grey(r), calib, f);
		return f;
	};
	const Eigen::Isometry3d T_kf = sim::SyntheticCorridor::examplePose(10, 0.3);
	const features::TStereoFrame kf = frameAt(T_kf, 1);
	ASSERT_GT(kf.meas.size(), 80u);
	std::vector<features::TStereoMeasurement> lm = kf.meas;
	std::mt19937 rng(3);
	for (size_t i = 0; i < lm.size(); i++)
	{
		if (i % 4 == 2)
		{
			lm[i].uL += 8;
			lm[i].uR += 8;
			calib.triangulate(lm[i].uL, lm[i].v, lm[i].uR, lm[i].P);
		}
		if (i % 4 == 3)
			for (auto& w : lm[i].desc.w) w = (uint64_t(rng()) << 32) | rng();
	}
	std::vector<features::TStereoFrame> frames;
	std::vector<survey::TReobservingFrame> in;
	for (int k = 1; k <= 3; k++) frames.push_back(frameAt(sim::SyntheticCorridor::examplePose(10 + k, 0.3), 1 + k));
	for (int k = 1; k <= 3; k++)
		in.push_back({&frames[k - 1], sim::SyntheticCorridor::examplePose(10 + k, 0.3).inverse() * T_kf});
	const auto m = survey::TReobservationMatching::From(vo::TStereoVOOptions(), 10.0);
	const auto n = survey::countReobservations(lm, calib, in, m);
	ASSERT_EQ(n.size(), lm.size());
	int stable = 0, stableSeen = 0, moved = 0, foreign = 0, hist[4] = {0, 0, 0, 0};
	for (size_t i = 0; i < lm.size(); i++)
	{
		EXPECT_LE(n[i], 3);
		if (i % 4 < 2) stable++, stableSeen += n[i] >= 2, hist[std::clamp(n[i], 0, 3)]++;
		if (i % 4 == 2) moved += n[i];
		if (i % 4 == 3) foreign += n[i];
	}
	std::printf("[reobservation] %zu landmarks: %d of %d stable ones re-found in >= 2 of 3 frames; moved %d, foreign %d credits (stable: %d %d %d %d)\n",
				lm.size(), stableSeen, stable, moved, foreign, hist[0], hist[1], hist[2], hist[3]);
	// FAST corners repeat only partly from frame to frame (here ~60 % of the
	// stable landmarks are re-found at least once, ~30 % in two or three
	// frames): that spread is what the score ranks by. The moved and foreign
	// landmarks must (almost) never score: one matched by chance and agreeing
	// with the pose is rare.
	EXPECT_GT(stable - hist[0], stable * 45 / 100);
	EXPECT_GT(stableSeen, stable / 5);
	EXPECT_LE(moved, static_cast<int>(lm.size()) / 40);
	EXPECT_LE(foreign, static_cast<int>(lm.size()) / 40);
	// No frames, no score; a frame without measurements is a caller's error.
	EXPECT_EQ(survey::countReobservations(lm, calib, {}, m), std::vector<int>(lm.size(), 0));
	EXPECT_THROW(survey::countReobservations(lm, calib, {survey::TReobservingFrame{}}, m), std::invalid_argument);
}

namespace
{
void writeSurveyCorridorRawlog(const std::string& rawlog, const std::string& gtTum, int n)
{
	sim::SyntheticCorridor corridor;
	const auto c = corridor.calib();
	io::RawlogWriter w(rawlog);
	io::Trajectory gt;
	for (int k = 0; k < n; k++)
	{
		const Eigen::Isometry3d T = sim::SyntheticCorridor::examplePose(k, 0.25);
		cv::Mat l, r;
		corridor.render(T, l, r, k);
		const double t = 1000.0 + 0.1 * k;
		w.write(test::stereoObservation(l, r, c, t));
		gt.push_back({t, T});
	}
	w.commit();
	io::writeTum(gtTum, gt);
}
}  // namespace

TEST(MapSurvey, SurveyAndMapInfoOnASyntheticRun)
{
	const std::string dir = test::tempDir("map_survey");
	const std::string rawlog = dir + "/corridor.rawlog", gt = dir + "/gt.tum", map = dir + "/corridor.kfmap";
	writeSurveyCorridorRawlog(rawlog, gt, 40);  // 10 m
	const std::string ini = dir + "/survey.ini";
	{
		std::ofstream f(ini);
		f << "[map]\nkf_spacing_m = 1.0\nlandmarks_per_keyframe = 60\ncompression_level = 3\n";
	}
	std::string out;
	ASSERT_EQ(test::runCommand(test::appPath() + " survey -i " + rawlog + " -o " + map + " -c " + ini + " --gt " + gt, &out), 0)
		<< out;
	const auto m = CKeyframeMap::LoadFromFile(map);
	// 9.75 m at 1 m spacing: 9 or 10 keyframes, one segment, both channels filled.
	EXPECT_GE(m->keyframeCount(), 9u) << out;
	EXPECT_LE(m->keyframeCount(), 11u) << out;
	EXPECT_EQ(m->runs(), std::vector<std::string>{"corridor"});
	for (const auto& k : m->keyframes())
	{
		EXPECT_EQ(k.segment, 0u);
		EXPECT_FALSE(k.predicted);
		ASSERT_TRUE(k.T_gt_kf);
		EXPECT_GT(k.channels[0].size(), 20u);
		EXPECT_LE(k.channels[0].size(), 60u);
		EXPECT_GT(k.channels[1].size(), 10u);
		EXPECT_LE(k.channels[1].size(), 60u);
	}
	EXPECT_TRUE(m->keyframe(0).T_map_kf.isApprox(Eigen::Isometry3d::Identity()));
	// The chain against the ground truth: the corridor VO is good to a few cm over 10 m.
	io::Trajectory est, g;
	for (const auto& k : m->keyframes())
	{
		est.push_back({k.timestamp, k.T_map_kf});
		g.push_back({k.timestamp, *k.T_gt_kf});
	}
	const auto e = eval::computeErrors(g, est, 1e-6);
	std::printf("[map-survey] %zu keyframes, ATE %.4f m\n", m->keyframeCount(), e.ate_rmse);
	EXPECT_LT(e.ate_rmse, 0.05);
	// The relative transforms agree with the poses along the chain.
	const auto r = m->relativePose(0, static_cast<uint32_t>(m->keyframeCount() - 1));
	EXPECT_TRUE(r.T_a_b.isApprox(m->keyframes().back().T_map_kf, 1e-6));
	EXPECT_GT(r.cov.trace(), 0);
	ASSERT_EQ(test::runCommand(test::appPath() + " map-info " + map, &out), 0) << out;
	EXPECT_NE(out.find("chain vs ground truth"), std::string::npos) << out;
	EXPECT_NE(out.find("MB/km"), std::string::npos) << out;
	// Bad input: clear errors, non-zero exit, no map left behind.
	const std::string none = dir + "/none.kfmap";
	EXPECT_NE(test::runCommand(test::appPath() + " survey -i " + dir + "/missing.rawlog -o " + none, &out), 0);
	EXPECT_NE(out.find("missing.rawlog"), std::string::npos) << out;
	EXPECT_NE(test::runCommand(test::appPath() + " survey -i " + rawlog + " -o " + dir + "/x.map", &out), 0);
	EXPECT_NE(out.find(".kfmap"), std::string::npos) << out;
	EXPECT_NE(test::runCommand(test::appPath() + " map-info " + rawlog, &out), 0);
	EXPECT_NE(out.find("corridor.rawlog"), std::string::npos) << out;
	// The chain's own channel cannot bridge its breaks.
	EXPECT_NE(test::runCommand(test::appPath() + " survey -i " + rawlog + " -o " + none + " --bridge mono", &out), 0);
	EXPECT_NE(out.find("--bridge 'mono'"), std::string::npos) << out;
	EXPECT_NE(out.find("(invariant)"), std::string::npos) << out;
	EXPECT_FALSE(std::filesystem::exists(none));
}

TEST(MapSurvey, AFilteredRunRecordsTheFilterThatMadeItsImages)
{
	// The same corridor surveyed twice: from a rawlog filtered by `shadyloc
	// filter` with a non-default invariant transform (no survey config: the
	// record, not the built-in channel, says how the images were made), and
	// from the colour rawlog with that transform in the survey's config
	// (filtered on the fly). Same images, so the same map.
	const std::string dir = test::tempDir("map_survey_filtered");
	const std::string raw = dir + "/corridor.rawlog", gt = dir + "/gt.tum", filtered = dir + "/corridor_f.rawlog";
	writeSurveyCorridorRawlog(raw, gt, 24);
	const std::string invSection =
		"[invariant]\nclass = CFilterInvariant\noutput_suffix = _inv\nalpha = 0.45\nbeta = 0.5\nscale = 100\n";
	{
		std::ofstream f(dir + "/filters.ini");
		f << "[filters]\npipeline = mono invariant\n[mono]\nclass = CFilterMonochrome\noutput_suffix = _mono\n"
		  << invSection;
		std::ofstream s(dir + "/survey.ini");
		s << "[map]\nkf_spacing_m = 1.0\ncompression_level = 3\n" << invSection;
		std::ofstream m(dir + "/map_only.ini");
		m << "[map]\nkf_spacing_m = 1.0\ncompression_level = 3\n";
	}
	std::string out;
	ASSERT_EQ(test::runCommand(test::appPath() + " filter -q -i " + raw + " -o " + filtered + " -c " + dir + "/filters.ini", &out), 0)
		<< out;
	ASSERT_EQ(
		test::runCommand(test::appPath() + " survey -i " + filtered + " -o " + dir + "/f.kfmap -c " + dir + "/map_only.ini", &out), 0)
		<< out;
	EXPECT_NE(out.find("from the filtered observations 'CAMERA_inv'"), std::string::npos) << out;
	EXPECT_NE(out.find("(filter record)"), std::string::npos) << out;	// warned: not the config's transform
	ASSERT_EQ(
		test::runCommand(test::appPath() + " survey -q -i " + raw + " -o " + dir + "/c.kfmap -c " + dir + "/survey.ini", &out), 0)
		<< out;
	const auto f = CKeyframeMap::LoadFromFile(dir + "/f.kfmap"), c = CKeyframeMap::LoadFromFile(dir + "/c.kfmap");
	const auto& inv = f->channels()[f->channelIndex("invariant")];
	EXPECT_EQ(inv.filter_class, "shadyloc::CFilterInvariant");
	EXPECT_NE(inv.filter_options.find("alpha = 0.45\n"), std::string::npos) << inv.filter_options;
	EXPECT_NE(inv.filter_options.find("scale = 100\n"), std::string::npos) << inv.filter_options;
	EXPECT_EQ(f->channels(), c->channels());
	ASSERT_EQ(f->keyframeCount(), c->keyframeCount());
	ASSERT_GT(f->keyframeCount(), 3u);
	for (uint32_t i = 0; i < f->keyframeCount(); i++)
	{
		EXPECT_TRUE(f->keyframe(i).T_map_kf.isApprox(c->keyframe(i).T_map_kf, 1e-12)) << "keyframe " << i;
		for (size_t ch = 0; ch < 2; ch++)
			EXPECT_EQ(f->keyframe(i).channels[ch].size(), c->keyframe(i).channels[ch].size()) << "keyframe " << i;
	}
	// The recorded filter is refused as live data by a map made with the default transform.
	EXPECT_THROW(c->checkCompatible(survey::channelParams("invariant", *filters::defaultChannel("invariant").filter,
														  features::TStereoFeatureOptions())),
				 std::runtime_error);
	// A channel the config does not define and no built-in has: named.
	EXPECT_NE(test::runCommand(test::appPath() + " survey -i " + raw + " -o " + dir + "/x.kfmap --channels mono,infrared", &out), 0);
	EXPECT_NE(out.find("infrared"), std::string::npos) << out;
	EXPECT_FALSE(std::filesystem::exists(dir + "/x.kfmap"));
}

namespace
{
/** A chain VO's run, 1 m a frame along z, whose VO breaks at frame 6 (a
 * Reinit whose dead reckoning is 2 m off), offered to a builder; with
 * `bridge` the break is linked by the true motion since the last map
 * keyframe, as the survey's bridge VO measures it. */
CKeyframeMap::Ptr buildAcrossABreak(bool bridge, std::vector<Eigen::Isometry3d>& truth)
{
	auto m = CKeyframeMap::Create();
	m->options.landmark_selection = TKeyframeMapOptions::LandmarkSelection::Strongest;
	m->options.kf_spacing_m = 1.5;
	const auto proto = test::makeSyntheticMap(1, 0, 0);
	m->setup(proto->calibration(), 512, 384, proto->channels());
	survey::SurveyBuilder b(*m, "run");
	auto at = [](double z) {
		Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
		T.translation().z() = z;
		return T;
	};
	std::vector<vo::TKeyframe> kfs;
	Eigen::Isometry3d T_world_lastMapKf = Eigen::Isometry3d::Identity();
	truth.clear();
	for (int f = 0; f < 12; f++)
	{
		vo::TFrameResult r;
		r.frame = static_cast<size_t>(f);
		r.timestamp = f;
		const size_t before = kfs.size();
		const Eigen::Isometry3d T_true = at(f);
		if (f == 0 || f == 6)
		{
			vo::TKeyframe k;
			k.frame = r.frame;
			k.chain_break = f == 6;
			// The break's link: dead reckoning 2 m short.
			k.T_world_kf = f == 0 ? T_true : at(f - 2.0);
			k.T_prevkf_kf = f == 0 ? Eigen::Isometry3d::Identity() : kfs.back().T_world_kf.inverse() * k.T_world_kf;
			k.cov = f == 0 ? geometry::Matrix6d::Zero() : geometry::Matrix6d(geometry::Matrix6d::Identity() * 1e2);
			kfs.push_back(k);
			r.status = f == 0 ? vo::FrameStatus::First : vo::FrameStatus::Reinit;
			r.keyframe = true;
			r.T_world_curr = k.T_world_kf;
		}
		else
		{
			r.status = vo::FrameStatus::Ok;
			r.T_kf_curr = at(f - static_cast<double>(kfs.back().frame));
			r.cov_kf_curr = geometry::Matrix6d::Identity() * 1e-6;
			r.T_world_curr = kfs.back().T_world_kf * r.T_kf_curr;
		}
		if (!b.offer(r, kfs, before)) continue;
		EXPECT_EQ(b.bridgeable(), f == 6) << "frame " << f;
		if (bridge && b.bridgeable()) b.bridge({T_world_lastMapKf.inverse() * T_true, geometry::Matrix6d::Identity() * 1e-4});
		b.addKeyframe({{}, {}});
		T_world_lastMapKf = T_true;
		truth.push_back(T_true);
	}
	b.finish();
	return m;
}
}  // namespace

TEST(MapSurvey, ABridgedBreakContinuesTheSegmentWhereTheBridgePutsIt)
{
	std::vector<Eigen::Isometry3d> truth;
	const auto bridged = buildAcrossABreak(true, truth);
	ASSERT_EQ(bridged->keyframeCount(), truth.size());
	for (size_t i = 0; i < truth.size(); i++)
	{
		const auto& k = bridged->keyframe(static_cast<uint32_t>(i));
		EXPECT_EQ(k.segment, 0u) << "keyframe " << i;
		EXPECT_FALSE(k.predicted) << "keyframe " << i;
		// The keyframes after the break too: the chain VO's world is re-anchored.
		EXPECT_LT((k.T_map_kf.translation() - truth[i].translation()).norm(), 1e-9) << "keyframe " << i;
	}
	EXPECT_NO_THROW(bridged->relativePose(0, static_cast<uint32_t>(truth.size() - 1)));
	// Unbridged: a new, predicted segment 2 m off.
	const auto broken = buildAcrossABreak(false, truth);
	const auto& last = broken->keyframes().back();
	EXPECT_EQ(last.segment, 1u);
	EXPECT_TRUE(last.predicted);
	EXPECT_NEAR((last.T_map_kf.translation() - truth.back().translation()).norm(), 2.0, 1e-9);
}
