/* The larger simulated evaluation set (config/sim_eval.ini, made by
 * scripts/make-eval-dataset.sh) is frozen: the localisers are tuned against
 * its conditions, so a change to them (options, path, or anything the
 * renderer makes of them) must be deliberate and visible.
 *
 * SimEvalFrozen.ConditionsAsSpecified checks what the set is for (six
 * lighting conditions including low sun from both sides, overcast and high
 * sun through the canopy; the whole route; one drive in the other lane).
 * SimEvalFrozen.FirstFramesMatchCommittedHashes compares, per traversal, the
 * hash of its options, its frame count, the hash of its ground-truth poses
 * and the hashes of its first two rendered stereo frames (full size, as the
 * script renders them) with tests/golden/sim_eval_frames.txt. A deliberate
 * change regenerates that file in the same commit:
 *   SHADYLOC_UPDATE_GOLDEN=1 build/tests/shadyloc_tests --gtest_filter='SimEvalFrozen.*'
 */
#include "../support/TestSupport.h"

#include <shadyloc/sim/StereoSimulator.h>

#include <gtest/gtest.h>

#include <mrpt/math/CQuaternion.h>

#include <opencv2/core.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

using namespace shadyloc::sim;

namespace
{
const std::string kConfig = std::string(SHADYLOC_SOURCE_DIR) + "/config/sim_eval.ini";
const std::string kGolden = std::string(SHADYLOC_SOURCE_DIR) + "/tests/golden/sim_eval_frames.txt";

/** FNV-1a, 64 bit. */
struct Fnv
{
	uint64_t h = 0xcbf29ce484222325ULL;
	void add(const void* p, size_t n)
	{
		const auto* b = static_cast<const uint8_t*>(p);
		for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ULL;
	}
	void add(const std::string& s) { add(s.data(), s.size()); }
	void add(const cv::Mat& m)
	{
		for (int r = 0; r < m.rows; r++) add(m.ptr(r), m.cols * m.elemSize());
	}
	std::string hex() const
	{
		char s[17];
		std::snprintf(s, sizeof(s), "%016llx", static_cast<unsigned long long>(h));
		return s;
	}
};

/** The options that make one traversal: camera, scene and its own section. */
std::string optionsText(const TSimOptions& o, const TTraversal& t)
{
	std::ostringstream s;
	o.camera.dumpToTextStream(s);
	o.scene.dumpToTextStream(s);
	t.dumpToTextStream(s);
	return s.str();
}

/** "name key=value ..." lines; '#' lines are comments. */
std::map<std::string, std::map<std::string, std::string>> readGolden(std::istream& in)
{
	std::map<std::string, std::map<std::string, std::string>> g;
	std::string line;
	while (std::getline(in, line))
	{
		if (line.empty() || line[0] == '#') continue;
		std::istringstream ss(line);
		std::string name, kv;
		ss >> name;
		while (ss >> kv)
		{
			const auto eq = kv.find('=');
			if (eq != std::string::npos) g[name][kv.substr(0, eq)] = kv.substr(eq + 1);
		}
	}
	return g;
}
}  // namespace

// What the set is for, checked on the options (no rendering).
TEST(SimEvalFrozen, ConditionsAsSpecified)
{
	auto o = TSimOptions::FromFile(kConfig);
	// The world of the default dataset: same camera and scene as config/sim.ini.
	const auto d = TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	std::ostringstream a, b;
	o.camera.dumpToTextStream(a);
	o.scene.dumpToTextStream(a);
	d.camera.dumpToTextStream(b);
	d.scene.dumpToTextStream(b);
	EXPECT_EQ(a.str(), b.str()) << "sim_eval.ini and sim.ini must describe the same camera and world";

	o.camera.width = 64;  // frame counts and poses only: a small camera is enough
	o.camera.height = 48;
	StereoSimulator sim(o);
	std::set<std::tuple<double, double, double, double, double, double, bool>> lights;
	bool overcast = false, dappled = false, lowLeftAhead = false, lowRightBehind = false;
	int otherLane = 0;
	for (const auto& t : o.traversals)
	{
		SCOPED_TRACE(t.name);
		// The whole route, from its start to (just past) its end: the lane's
		// length differs from the centre line's by a few centimetres on the
		// S-curve, so the traversals end 1 m past it to be 300 m long.
		ASSERT_TRUE(t.endsByDistance());
		EXPECT_EQ(o.scene.route_length_m, 300.0);
		EXPECT_EQ(t.start_s_m, 0.0);
		EXPECT_EQ(t.end_s_m, 301.0);
		sim.setTraversal(t);
		const int n = sim.frameCount();
		EXPECT_GE(sim.routePosition(n - 1), 301.0);
		double length = 0;
		for (int i = 1; i < n; i++)
		{
			const auto p = sim.T_world_left(i), q = sim.T_world_left(i - 1);
			length += std::hypot(p.x() - q.x(), p.y() - q.y());
		}
		EXPECT_GE(length, 300.0) << "ground-truth path length of the left camera";

		if (std::abs(t.lateral_offset_m - 3.5) < 1e-9)
		{
			otherLane++;  // the other lane: not one of the lighting conditions
			continue;
		}
		EXPECT_LT(std::abs(t.lateral_offset_m), 0.5) << "in the right-hand lane";
		lights.insert({t.overcast ? 0 : t.sun_azimuth_deg, t.overcast ? 0 : t.sun_elevation_deg,
			t.overcast ? 0 : t.sun_temperature_K, t.sky_temperature_K, t.effectiveSunIrradiance(), t.sky_irradiance,
			t.overcast});
		const double az = t.sun_azimuth_deg * M_PI / 180;  // the route heads east (azimuth 90 deg)
		overcast |= t.overcast;
		if (t.overcast) continue;
		dappled |= t.sun_elevation_deg >= 55;  // high sun through the avenue's crowns
		// Low sun from both sides: ahead-left (north-east) and behind-right (south-west).
		lowLeftAhead |= t.sun_elevation_deg <= 15 && std::cos(az) > 0.2 && std::sin(az) > 0.2;
		lowRightBehind |= t.sun_elevation_deg <= 15 && std::cos(az) < -0.2 && std::sin(az) < -0.2;
	}
	EXPECT_GE(lights.size(), 6u) << "distinct lighting conditions";
	EXPECT_TRUE(overcast);
	EXPECT_TRUE(dappled);
	EXPECT_TRUE(lowLeftAhead);
	EXPECT_TRUE(lowRightBehind);
	EXPECT_EQ(otherLane, 1) << "one traversal 3.5 m to the side, in the other lane";
}

// The conditions as rendered: options, frame count, ground truth and the
// first two frames of every traversal against the committed hashes.
TEST(SimEvalFrozen, FirstFramesMatchCommittedHashes)
{
	const auto o = TSimOptions::FromFile(kConfig);
	StereoSimulator sim(o);
	std::ostringstream now;
	now << "# config/sim_eval.ini, frozen (tests/unit/test_sim_eval.cpp): per traversal, FNV-1a 64 of its\n"
		   "# options (camera, scene and its section as dumped), its frame count, FNV-1a 64 of its\n"
		   "# ground-truth poses (T_world_left of every frame, %.6f m and %.9f quaternion) and of\n"
		   "# the left and right BGR bytes of frames 0 and 1 (rendered in order, 512x384).\n"
		   "# Regenerate after a deliberate change: SHADYLOC_UPDATE_GOLDEN=1 build/tests/shadyloc_tests "
		   "--gtest_filter='SimEvalFrozen.*'\n";
	for (const auto& t : o.traversals)
	{
		sim.setTraversal(t);
		const int n = sim.frameCount();
		Fnv opts, poses, f0, f1;
		opts.add(optionsText(o, t));
		for (int i = 0; i < n; i++)
		{
			const auto T = sim.T_world_left(i);
			mrpt::math::CQuaternionDouble q;
			T.getAsQuaternion(q);
			char s[160];
			std::snprintf(s, sizeof(s), "%.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", T.x(), T.y(), T.z(), q.x(), q.y(),
				q.z(), q.r());
			poses.add(std::string(s));
		}
		const TSimFrame a = sim.renderFrame(0), b = sim.renderFrame(1);
		f0.add(a.left);
		f0.add(a.right);
		f1.add(b.left);
		f1.add(b.right);
		now << t.name << " options=" << opts.hex() << " frames=" << n << " poses=" << poses.hex()
			<< " frame0=" << f0.hex() << " frame1=" << f1.hex() << "\n";
	}
	if (shadyloc::test::updatingGolden())
	{
		std::ofstream(kGolden) << now.str();
		GTEST_SKIP() << "wrote " << kGolden << " (SHADYLOC_UPDATE_GOLDEN is set): review `git diff tests/golden`";
	}
	std::ifstream f(kGolden);
	ASSERT_TRUE(f.good()) << kGolden << " missing";
	const auto want = readGolden(f);
	std::istringstream nowIn(now.str());
	const auto got = readGolden(nowIn);
	ASSERT_EQ(got.size(), want.size()) << "traversals of config/sim_eval.ini changed:\n" << now.str();
	const std::map<std::string, std::string> why = {
		{"options", "its options (config/sim_eval.ini or an option's default or dump) changed"},
		{"frames", "its frame count changed (speed, start or end)"},
		{"poses", "its ground-truth path changed"},
		{"frame0", "the renderer makes other pixels of these conditions"},
		{"frame1", "the renderer makes other pixels of these conditions (auto-exposure over frames?)"}};
	for (const auto& [name, fields] : want)
	{
		const auto it = got.find(name);
		ASSERT_NE(it, got.end()) << "traversal " << name << " no longer in config/sim_eval.ini";
		for (const auto& [key, msg] : why)
			EXPECT_EQ(it->second.at(key), fields.count(key) ? fields.at(key) : "")
				<< name << " " << key << ": " << msg
				<< "; the evaluation set is frozen: if meant, regenerate tests/golden/sim_eval_frames.txt "
				   "(see config/sim_eval.ini)";
	}
}
