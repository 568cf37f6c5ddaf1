/* Tests of maps of several experiences (survey/AppendExperience.h): a run
 * appended through verified links is placed in the map frame, a wrong link
 * closes no loop, a run that localises nowhere keeps its own frame and is
 * never related to the others, other cameras or descriptors are refused
 * naming both, experiences survive saving and loading, and a broken link
 * or a missing experience is reported and left out while the rest loads. */
#include <shadyloc/localisation/FixAcceptance.h>
#include <shadyloc/localisation/FixEstimate.h>
#include <shadyloc/survey/AppendExperience.h>

#include "../support/TestSupport.h"
#include "test_map_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/serialization/CArchive.h>

using namespace shadyloc;

namespace
{
/** The base map's route driven again `O` aside (in each keyframe's frame),
 * its own frame `G` away from the map's: what a second survey of the road
 * would give. Ground truth moves with it. */
CKeyframeMap::Ptr drivenAgain(const CKeyframeMap& base, const Eigen::Isometry3d& G, const Eigen::Isometry3d& O)
{
	auto m = CKeyframeMap::Create();
	m->options = base.options;
	m->setup(base.calibration(), base.imageWidth(), base.imageHeight(), base.channels());
	const uint16_t run = m->addRun("again");
	for (const auto& k0 : base.keyframes())
	{
		map::TMapKeyframe k = k0;
		k.run = run;
		k.T_map_kf = G * k0.T_map_kf * O;
		k.T_prev_kf = O.inverse() * k0.T_prev_kf * O;
		if (k0.T_gt_kf) k.T_gt_kf = *k0.T_gt_kf * O;
		m->appendKeyframe(std::move(k));
	}
	return m;
}

Eigen::Isometry3d aside(double x)
{
	Eigen::Isometry3d O = Eigen::Isometry3d::Identity();
	O.translation() = Eigen::Vector3d(x, 0, 0.3);
	return O;
}

Eigen::Isometry3d elsewhere()
{
	Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
	G.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()).toRotationMatrix();
	G.translation() = Eigen::Vector3d(40, 1, -25);
	return G;
}

/** Fixes of the run's keyframes in the base map's keyframes, as the
 * localisation system reports them (sigma 2 cm). */
std::vector<survey::TRunFix> fixesOf(const CKeyframeMap& run, const Eigen::Isometry3d& O)
{
	std::vector<survey::TRunFix> f;
	for (const auto& k : run.keyframes())
		f.push_back({k.frame, k.id, O, geometry::Matrix6d::Identity() * 4e-4});
	return f;
}
/** `base` and its route driven again 1 m aside, linked at every keyframe (run "again"). */
CKeyframeMap withLinkedRun(const CKeyframeMap& base)
{
	CKeyframeMap m = base;
	survey::appendExperience(m, *drivenAgain(base, elsewhere(), aside(1.0)), "again", fixesOf(base, aside(1.0)));
	return m;
}

/** `m` and the other lane of `base`'s route (3.5 m aside), localised
 * nowhere, so kept in a frame of its own (run "other_lane"). */
CKeyframeMap withOtherLane(CKeyframeMap m, const CKeyframeMap& base)
{
	survey::appendExperience(m, *drivenAgain(base, elsewhere(), aside(3.5)), "other_lane", {});
	return m;
}
}  // namespace

TEST(Experiences, AppendedRunIsPlacedInTheMapFrameThroughVerifiedLinks)
{
	const auto base = test::makeSyntheticMap(24, 30, 0);
	const Eigen::Isometry3d O = aside(1.5), G = elsewhere();
	const auto run = drivenAgain(*base, G, O);
	auto fixes = fixesOf(*run, O);
	// A wrong fix: keyframe 10's frame placed at keyframe 16.
	fixes[10].kf = 16;
	CKeyframeMap m = *base;
	const auto rep = survey::appendExperience(m, *run, "again", fixes);
	ASSERT_TRUE(rep.anchored);
	EXPECT_EQ(rep.candidates.size(), 24u);
	EXPECT_EQ(rep.verified(), 23u);
	EXPECT_FALSE(rep.candidates[10].verified) << "a wrong link closes no loop";
	EXPECT_GT(*rep.candidates[10].err_m, 5.0);
	EXPECT_LT(*rep.candidates[3].err_m, 1e-9);
	ASSERT_EQ(m.runs().size(), 2u);
	EXPECT_EQ(m.keyframeCount(), 48u);
	EXPECT_EQ(m.links().size(), 23u);
	for (uint32_t i = 0; i < 24; i++)
	{
		// The new keyframe lies O from its base keyframe, in the map frame (not G away).
		const Eigen::Isometry3d want = base->keyframe(i).T_map_kf * O;
		EXPECT_LT((m.keyframe(24 + i).T_map_kf.translation() - want.translation()).norm(), 1e-9) << "keyframe " << i;
		EXPECT_EQ(m.frameOf(24 + i), 0u);
	}
	// Related through the links: the relative pose across runs and its covariance.
	const auto r = m.measuredRelativePose(5, 24 + 7);
	ASSERT_TRUE(r.has_value());
	const Eigen::Isometry3d want = base->keyframe(5).T_map_kf.inverse() * base->keyframe(7).T_map_kf * O;
	EXPECT_LT((r->T_a_b.translation() - want.translation()).norm(), 1e-9);
	EXPECT_GT(r->cov(0, 0), 4e-4);
	// The input of the append is what it was when anything throws.
	CKeyframeMap again = m;
	EXPECT_THROW(survey::appendExperience(again, *run, "again", fixes), std::runtime_error);
	EXPECT_EQ(again.keyframeCount(), 48u);
}

TEST(Experiences, ARunLocalisedNowhereKeepsItsOwnFrameAndIsNeverRelated)
{
	const auto base = test::makeSyntheticMap(24, 30, 0);
	const auto run = drivenAgain(*base, elsewhere(), aside(3.5));
	CKeyframeMap m = *base;
	// One fix only (and a wrong one): nothing to verify it, nothing to anchor.
	std::vector<survey::TRunFix> fixes = {{run->keyframe(3).frame, 12, aside(0), geometry::Matrix6d::Identity() * 4e-4}};
	const auto rep = survey::appendExperience(m, *run, "other_lane", fixes);
	EXPECT_FALSE(rep.anchored);
	EXPECT_EQ(rep.verified(), 0u);
	EXPECT_TRUE(m.links().empty());
	EXPECT_FALSE(m.runAnchored(1));
	EXPECT_EQ(m.frameOf(30), 1u);
	// Its poses stay in its own frame; a spatial query in one frame never returns the other's keyframes.
	EXPECT_LT((m.keyframe(30).T_map_kf.translation() - run->keyframe(6).T_map_kf.translation()).norm(), 1e-12);
	map::TNearestQuery q;
	q.max_distance_m = 200;
	q.max_angle_deg = 180;
	q.max_results = 1000;
	q.same_frame_as = 0;
	for (const auto& h : m.nearestKeyframes(m.keyframe(5).T_map_kf, q)) EXPECT_LT(h.id, 24u);
	q.same_frame_as = 30;
	const auto hits = m.nearestKeyframes(m.keyframe(30).T_map_kf, q);
	EXPECT_EQ(hits.size(), 24u);
	for (const auto& h : hits) EXPECT_GE(h.id, 24u);
	// No measured relation, and a localiser's link between them is one no test passes.
	EXPECT_FALSE(m.measuredRelativePose(5, 30).has_value());
	const auto link = localisation::keyframeLink(m, localisation::TLocaliserOptions{}, 5, 30);
	EXPECT_TRUE(std::isinf(localisation::mahalanobis2(geometry::Vector6d::Zero(), link.cov)));
	// Within one run the chain still relates keyframes.
	const auto within = localisation::keyframeLink(m, localisation::TLocaliserOptions{}, 5, 9);
	EXPECT_TRUE(within.cov.allFinite());
}

// A run that localises against an experience kept in a frame of its own is
// placed in that frame, not in the map frame its keyframes' poses do not
// belong to.
TEST(Experiences, ARunLinkedToAnExperienceInItsOwnFrameIsPlacedInThatFrame)
{
	const auto base = test::makeSyntheticMap(16, 10, 0);
	const Eigen::Isometry3d G = elsewhere(), O = aside(0.5);
	const auto lane = drivenAgain(*base, G, aside(3.5));
	CKeyframeMap m = *base;
	survey::appendExperience(m, *lane, "other_lane", {});
	ASSERT_EQ(m.frameOf(16), 1u);
	// The next run: fixes in the other-lane experience's keyframes (ids 16..31).
	const auto next = drivenAgain(*lane, Eigen::Isometry3d::Identity(), O);
	std::vector<survey::TRunFix> fixes;
	for (const auto& k : next->keyframes()) fixes.push_back({k.frame, 16 + k.id, O, geometry::Matrix6d::Identity() * 4e-4});
	const auto rep = survey::appendExperience(m, *next, "other_lane_again", fixes);
	ASSERT_TRUE(rep.anchored);
	EXPECT_EQ(rep.frame_of, "other_lane");
	EXPECT_EQ(m.runFrame(2), 1u);
	EXPECT_FALSE(m.runAnchored(2));
	for (uint32_t i = 0; i < 16; i++)
	{
		EXPECT_EQ(m.frameOf(32 + i), 1u);
		const Eigen::Isometry3d want = m.keyframe(16 + i).T_map_kf * O;
		EXPECT_LT((m.keyframe(32 + i).T_map_kf.translation() - want.translation()).norm(), 1e-9) << "keyframe " << i;
	}
	// A frame that does not exist, or is not a founder, is refused.
	CKeyframeMap bad = m;
	EXPECT_THROW(bad.addRun("x", 7), std::invalid_argument);
	EXPECT_THROW(bad.addRun("y", 2), std::invalid_argument);
}

TEST(Experiences, AnotherCameraOrDescriptorIsRefusedNamingBoth)
{
	const auto base = test::makeSyntheticMap(12, 10, 0);
	for (const int mutation : {test::kCalibFx, test::kChannelSeed, test::kOptLandmarks})
	{
		const auto other = test::makeSyntheticMap(12, 10, 0, mutation);
		CKeyframeMap m = *base;
		try
		{
			survey::appendExperience(m, *other, "other", {});
			ADD_FAILURE() << "mutation " << mutation << " was appended";
		}
		catch (const std::runtime_error& e)
		{
			const std::string msg = e.what();
			EXPECT_NE(msg.find("map:"), std::string::npos) << msg;
			EXPECT_NE(msg.find("new run:"), std::string::npos) << msg;
			if (mutation == test::kCalibFx)
			{
				EXPECT_NE(msg.find("camera"), std::string::npos) << msg;
			}
			if (mutation == test::kChannelSeed)
			{
				EXPECT_NE(msg.find("descriptor"), std::string::npos) << msg;
			}
			if (mutation == test::kOptLandmarks)
			{
				EXPECT_NE(msg.find("landmarks_per_keyframe"), std::string::npos) << msg;
			}
		}
		EXPECT_EQ(m.keyframeCount(), 12u);
		EXPECT_EQ(m.runs().size(), 1u);
	}
}

TEST(Experiences, ExperiencesAndLinksSurviveSavingAndLoading)
{
	const auto base = test::makeSyntheticMap(16, 10, 0);
	CKeyframeMap m = withOtherLane(withLinkedRun(*base), *base);
	mrpt::io::CMemoryStream buf;
	mrpt::serialization::archiveFrom(buf) << m;
	buf.Seek(0);
	CKeyframeMap loaded;
	mrpt::serialization::archiveFrom(buf) >> loaded;
	ASSERT_EQ(loaded.runs(), m.runs());
	EXPECT_TRUE(loaded.runAnchored(1));
	EXPECT_FALSE(loaded.runAnchored(2));
	ASSERT_EQ(loaded.links().size(), m.links().size());
	ASSERT_FALSE(m.links().empty());
	for (size_t i = 0; i < m.links().size(); i++)
	{
		EXPECT_EQ(loaded.links()[i].a, m.links()[i].a);
		EXPECT_EQ(loaded.links()[i].b, m.links()[i].b);
		EXPECT_TRUE(loaded.links()[i].T_a_b.isApprox(m.links()[i].T_a_b, 0));
		EXPECT_TRUE(loaded.links()[i].cov.isApprox(m.links()[i].cov, 0));
	}
	EXPECT_EQ(loaded.frameOf(40), 2u);
	EXPECT_EQ(loaded.runFrame(2), 2u);
}

TEST(Experiences, ABrokenLinkOrAMissingExperienceIsReportedAndLeftOut)
{
	const auto base = test::makeSyntheticMap(16, 10, 0);
	CKeyframeMap m = withOtherLane(withLinkedRun(*base), *base);
	const size_t intact = m.links().size();
	ASSERT_GT(intact, 10u);
	// A link that contradicts the poses it placed (2 m off, sigma 2 cm), one
	// across frames (nothing to compare it with: kept), and an experience
	// whose keyframes are gone.
	map::TExperienceLink wrong = m.links()[4];
	wrong.T_a_b.translation() += Eigen::Vector3d(2, 0, 0);
	m.addLink(wrong);
	map::TExperienceLink across = m.links()[0];
	across.b = 40;	// a keyframe of other_lane, in a frame of its own
	m.addLink(across);
	m.addRun("pruned");
	mrpt::io::CMemoryStream buf;
	mrpt::serialization::archiveFrom(buf) << m;
	buf.Seek(0);
	CKeyframeMap loaded;
	mrpt::serialization::archiveFrom(buf) >> loaded;
	EXPECT_EQ(loaded.links().size(), intact + 1) << "the wrong link left out, the rest kept";
	ASSERT_EQ(loaded.loadProblems().size(), 2u);
	const std::string linkMsg = loaded.loadProblems()[0], runMsg = loaded.loadProblems()[1];
	EXPECT_NE(linkMsg.find("link " + std::to_string(intact) + " (keyframes " + std::to_string(wrong.a) + ", " + std::to_string(wrong.b) + ")"), std::string::npos) << linkMsg;
	EXPECT_NE(linkMsg.find("2.000 m apart"), std::string::npos) << linkMsg;
	EXPECT_NE(runMsg.find("run 3 ('pruned'): no keyframe"), std::string::npos) << runMsg;
	// The rest relates as before: across the runs through the intact links.
	const auto r = loaded.measuredRelativePose(wrong.a, wrong.b);
	ASSERT_TRUE(r.has_value());
	const Eigen::Isometry3d want = m.keyframe(wrong.a).T_map_kf.inverse() * m.keyframe(wrong.b).T_map_kf;
	EXPECT_LT((r->T_a_b.translation() - want.translation()).norm(), 1e-6);
	std::ostringstream report;
	loaded.reportLoadProblems(report, "two.kfmap");
	EXPECT_EQ(report.str().rfind("warning: map 'two.kfmap': link ", 0), 0u) << report.str();
	// A sound map reports nothing.
	mrpt::io::CMemoryStream sound;
	mrpt::serialization::archiveFrom(sound) << *base;
	sound.Seek(0);
	mrpt::serialization::archiveFrom(sound) >> loaded;
	EXPECT_TRUE(loaded.loadProblems().empty());
}

TEST(Experiences, AnExperienceInAFrameOfItsOwnIsNotDrawnInTheMapFrame)
{
	const auto base = test::makeSyntheticMap(16, 10, 0);
	const CKeyframeMap linked = withLinkedRun(*base), withOwn = withOtherLane(linked, *base);
	ASSERT_FALSE(withOwn.runAnchored(2));
	// Triangles (path and chevrons) and landmark points of a drawing.
	const auto drawn = [](CKeyframeMap m) {
		m.options.draw_landmarks = true;
		mrpt::opengl::CSetOfObjects scene;
		m.getVisualizationInto(scene);
		std::pair<size_t, size_t> n{0, 0};
		for (const auto& o : scene)
			if (const auto t = std::dynamic_pointer_cast<mrpt::opengl::CSetOfTriangles>(o))
				n.first += t->getTrianglesCount();
			else if (const auto c = std::dynamic_pointer_cast<mrpt::opengl::CPointCloudColoured>(o))
				n.second += c->size();
		return n;
	};
	const auto a = drawn(linked), b = drawn(withOwn);
	EXPECT_GT(a.first, 0u);
	EXPECT_GT(a.second, 0u);
	EXPECT_EQ(b, a) << "the other lane's keyframes and landmarks are not in the map frame";
}

// `shadyloc survey --append` on the default dataset: the overcast run added
// to a map of the noon run is linked where it localises, the links agree
// with the ground truth, the input map is never touched, bad input is
// refused naming what is at fault, with no output left, and a broken link
// is reported while the rest of the map localises.
TEST(ExperiencesApp, AppendedRunIsLinkedAndTheInputMapIsUntouched)
{
	SHADYLOC_REQUIRE_DEFAULT_DATASET();
	const std::string src = SHADYLOC_SOURCE_DIR, data = test::defaultDatasetDir(), app = test::appPath();
	const std::string dir = test::tempDir("experiences_app");
	const std::string one = dir + "/one.kfmap", two = dir + "/two.kfmap", links = dir + "/links.csv";
	const std::string vo = " -c " + src + "/config/vo_sim.ini", loc = vo + " -c " + src + "/config/localise_sim.ini";
	std::string out;
	ASSERT_EQ(test::runCommand(app + " survey -q -i " + data + "/noon.rawlog --gt " + data + "/noon.tum -o " + one + vo, &out), 0)
		<< out;
	const std::string before = test::fileContents(one);
	const std::string append = app + " survey --append " + one + " -i " + data + "/overcast.rawlog --gt " + data + "/overcast.tum";
	ASSERT_EQ(test::runCommand(append + " -o " + two + " --links " + links + loc, &out), 0) << out;
	EXPECT_NE(out.find("anchored in the frame of 'noon'"), std::string::npos) << out;
	const auto m = CKeyframeMap::LoadFromFile(two);
	ASSERT_EQ(m->runs(), (std::vector<std::string>{"noon", "overcast"}));
	EXPECT_TRUE(m->runAnchored(1));
	// Links: most of the run's keyframes, each within the 0.5 m / 2 deg of a true fix.
	std::ifstream f(links);
	std::string line;
	std::getline(f, line);
	size_t verified = 0;
	std::vector<double> err;
	while (std::getline(f, line))
	{
		std::vector<std::string> c;
		std::stringstream ss(line);
		for (std::string x; std::getline(ss, x, ',');) c.push_back(x);
		ASSERT_GE(c.size(), 10u) << line;
		if (c[2] != "1") continue;
		verified++;
		err.push_back(std::stod(c[8]));
		EXPECT_LT(std::stod(c[8]), 0.5) << line;
		EXPECT_LT(std::stod(c[9]), 2.0) << line;
	}
	const size_t newKf = m->keyframeCount() - CKeyframeMap::LoadFromFile(one)->keyframeCount();
	EXPECT_EQ(m->links().size(), verified);
	EXPECT_GE(verified, newKf / 2) << out;
	ASSERT_FALSE(err.empty());
	std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
	EXPECT_LT(err[err.size() / 2], 0.05) << "median link error";
	// The input map, byte for byte.
	EXPECT_EQ(test::fileContents(one), before);
	// Bad input: the map as output, other [map] options, a run name the map holds.
	EXPECT_NE(test::runCommand(append + " -o " + one + loc, &out), 0);
	EXPECT_NE(out.find(one), std::string::npos) << out;
	EXPECT_EQ(test::fileContents(one), before);
	const std::string layer = dir + "/fewer.ini", three = dir + "/three.kfmap";
	std::ofstream(layer) << "[map]\nlandmarks_per_keyframe = 100\n";
	EXPECT_NE(test::runCommand(append + " -o " + three + loc + " -c " + layer, &out), 0);
	EXPECT_NE(out.find("landmarks_per_keyframe"), std::string::npos) << out;
	EXPECT_NE(out.find("new run:"), std::string::npos) << out;
	const std::string again = app + " survey --append " + two + " -i " + data + "/overcast.rawlog -o " + three + loc;
	EXPECT_NE(test::runCommand(again, &out), 0);
	EXPECT_NE(out.find("already holds a run named 'overcast'"), std::string::npos) << out;
	EXPECT_FALSE(std::filesystem::exists(three));

	// A map with a broken link (2 m off the poses it placed) says so, and
	// localises against the rest exactly as the map without that link.
	auto broken = CKeyframeMap::LoadFromFile(two);
	map::TExperienceLink wrong = broken->links()[3];
	wrong.T_a_b.translation() += Eigen::Vector3d(2, 0, 0);
	broken->addLink(wrong);
	const std::string bad = dir + "/broken.kfmap", live = " -i " + data + "/evening_warm.rawlog" + loc;
	broken->saveToFile(bad);
	ASSERT_EQ(test::runCommand(app + " localise -q -m " + two + live + " -o " + dir + "/loc_two", &out), 0) << out;
	std::smatch cov;
	ASSERT_TRUE(std::regex_search(out, cov, std::regex("coverage ([0-9.]+) %"))) << out;
	EXPECT_GT(std::stod(cov[1]), 50.0) << out;
	ASSERT_EQ(test::runCommand(app + " localise -q -m " + bad + live + " -o " + dir + "/loc_broken", &out), 0) << out;
	EXPECT_NE(out.find("warning: map '" + bad + "': link " + std::to_string(broken->links().size() - 1)), std::string::npos)
		<< out;
	EXPECT_EQ(test::fileContents(dir + "/loc_broken/frames.csv"), test::fileContents(dir + "/loc_two/frames.csv"));
}

// `shadyloc localise --learn`: the evening run against the noon map with the
// baseline (which goes blind at the start of the run) adds its keyframes
// there, and only there, linked by the fixes after them; a run with no blind
// stretch that long adds nothing; the map is never the output.
TEST(ExperiencesApp, LearnAddsKeyframesOnlyWhereTheRunWentBlind)
{
	SHADYLOC_REQUIRE_DEFAULT_DATASET();
	const std::string src = SHADYLOC_SOURCE_DIR, data = test::defaultDatasetDir(), app = test::appPath();
	const std::string dir = test::tempDir("experiences_learn");
	const std::string map = dir + "/noon.kfmap", learnt = dir + "/learnt.kfmap";
	const std::string cfg = " -c " + src + "/config/vo_sim.ini -c " + src + "/config/localise_sim.ini";
	std::string out;
	ASSERT_EQ(
		test::runCommand(app + " survey -q -i " + data + "/noon.rawlog --gt " + data + "/noon.tum -o " + map + " -c " + src + "/config/vo_sim.ini", &out),
		0)
		<< out;
	const std::string before = test::fileContents(map);
	const std::string loc = app + " localise -m " + map + " -i " + data + "/evening_warm.rawlog --gt " + data +
							"/evening_warm.tum --localisers mono" + cfg;
	// A 10 m margin: linking needs 3 fixes that close loops with each other,
	// and 5 m after this 8.5 m blind start hold only 3 keyframes with a fix
	// (one that disagrees leaves the experience in its own frame).
	ASSERT_EQ(
		test::runCommand(loc + " -o " + dir + "/loc --learn " + learnt + " --learn-blind-m 2 --learn-margin-m 10", &out), 0)
		<< out;
	EXPECT_NE(out.find("learn: "), std::string::npos) << out;
	const auto base = CKeyframeMap::LoadFromFile(map), m = CKeyframeMap::LoadFromFile(learnt);
	ASSERT_EQ(m->runs(), (std::vector<std::string>{"noon", "evening_warm"}));
	const size_t added = m->keyframeCount() - base->keyframeCount();
	EXPECT_GT(added, 0u) << out;
	EXPECT_LT(added, base->keyframeCount() / 2) << "only the blind stretches, not the run: " << out;
	EXPECT_TRUE(m->runAnchored(1)) << out;
	EXPECT_FALSE(m->links().empty());
	EXPECT_EQ(test::fileContents(map), before);
	// Nothing that long: the output is the map as it was.
	ASSERT_EQ(test::runCommand(loc + " -o " + dir + "/loc2 --learn " + dir + "/same.kfmap --learn-blind-m 1000", &out), 0) << out;
	EXPECT_NE(out.find("nothing to learn"), std::string::npos) << out;
	EXPECT_EQ(CKeyframeMap::LoadFromFile(dir + "/same.kfmap")->keyframeCount(), base->keyframeCount());
	// The map as the output: refused before any work, the map untouched.
	EXPECT_NE(test::runCommand(loc + " -o " + dir + "/loc3 --learn " + map, &out), 0);
	EXPECT_NE(out.find(map), std::string::npos) << out;
	EXPECT_EQ(test::fileContents(map), before);
	EXPECT_FALSE(std::filesystem::exists(dir + "/loc3"));
}
