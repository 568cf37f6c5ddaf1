/* `shadyloc sim` end to end: a small dataset comes out complete and
 * readable; bad input fails with a clear message and leaves nothing behind. */
#include "../support/TestSupport.h"

#include <shadyloc/io/Rawlog.h>
#include <shadyloc/sim/StereoSimulator.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using shadyloc::test::appPath;
using shadyloc::test::runCommand;
using shadyloc::test::tempDir;

namespace
{
/** The shipped config with a tiny camera and 3 frames per traversal, plus
 * an optional replacement of one line (to inject errors). */
std::string tinyConfig(const std::string& dir, const std::string& from = "", const std::string& to = "")
{
	std::ifstream in(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	std::stringstream ss;
	ss << in.rdbuf();
	std::string s = ss.str();
	s = std::regex_replace(s, std::regex("\nwidth_px = 512"), "\nwidth_px = 96");
	s = std::regex_replace(s, std::regex("\nheight_px = 384"), "\nheight_px = 72");
	s = std::regex_replace(s, std::regex("\nend_s_m = 170[^\n]*"), "\nframes = 3");
	if (!from.empty())
	{
		const auto at = s.find(from);
		EXPECT_NE(at, std::string::npos) << from;
		if (at != std::string::npos) s.replace(at, from.size(), to);
	}
	const std::string path = dir + "/sim.ini";
	std::ofstream(path) << s;
	return path;
}

size_t filesIn(const std::string& dir)
{
	if (!fs::is_directory(dir)) return 0;
	size_t n = 0;
	for (const auto& e : fs::recursive_directory_iterator(dir)) n += e.is_regular_file();
	return n;
}
}  // namespace

TEST(SimApp, WritesRawlogsAndGroundTruth)
{
	const std::string dir = tempDir("sim_app_ok");
	const std::string cfg = tinyConfig(dir);
	std::string out;
	ASSERT_EQ(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/out --traversals noon,overcast", &out), 0)
		<< out;
	for (const std::string t : {"noon", "overcast"})
	{
		shadyloc::io::RawlogReader r(dir + "/out/" + t + ".rawlog");
		int n = 0;
		std::vector<double> stamps;
		while (auto obj = r.next())
		{
			auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(obj);
			ASSERT_TRUE(obs) << "object " << n << " is not a stereo observation";
			EXPECT_EQ(obs->sensorLabel, "CAMERA");
			EXPECT_TRUE(obs->hasImageRight);
			EXPECT_TRUE(obs->imageLeft.isColor());
			EXPECT_EQ(obs->imageLeft.getWidth(), 96u);
			EXPECT_EQ(obs->leftCamera.ncols, 96u);
			EXPECT_NEAR(obs->rightCameraPose.x(), 0.12, 1e-12);
			stamps.push_back(mrpt::Clock::toDouble(obs->timestamp));
			n++;
		}
		EXPECT_EQ(n, 3) << t;
		std::ifstream tum(dir + "/out/" + t + ".tum");
		std::string line;
		int rows = 0;
		while (std::getline(tum, line))
			if (!line.empty() && line[0] != '#')
			{
				ASSERT_LT(rows, 3);
				EXPECT_NEAR(std::stod(line), stamps[static_cast<size_t>(rows)], 1e-4);
				rows++;
			}
		EXPECT_EQ(rows, 3) << t;
	}
	EXPECT_FALSE(fs::exists(dir + "/out/morning_low_sun.rawlog"));	// only the traversals asked for
}

TEST(SimApp, BadOptionNamesFileSectionKey)
{
	const std::string dir = tempDir("sim_app_badkey");
	const std::string cfg = tinyConfig(dir, "\nhfov_deg = 65", "\nhfov_dgr = 65");
	std::string out;
	EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/out", &out), 0);
	EXPECT_NE(out.find("sim.ini"), std::string::npos) << out;
	EXPECT_NE(out.find("[sim.camera] hfov_dgr: unknown key; did you mean 'hfov_deg'?"), std::string::npos) << out;
	EXPECT_EQ(filesIn(dir + "/out"), 0u);
}

TEST(SimApp, BadValueIsRejected)
{
	const std::string dir = tempDir("sim_app_badvalue");
	for (const auto& [from, to, msg] : std::vector<std::tuple<std::string, std::string, std::string>>{
			 {"\nbaseline_m = 0.12", "\nbaseline_m = twelve", "[sim.camera] baseline_m: 'twelve' is not a number"},
			 {"\nsensitivity_sigma_nm = 30", "\nsensitivity_sigma_nm = -3", "sensitivity_sigma_nm"},
			 {"\nsun_elevation_deg = 55", "\nsun_elevation_deg = 95", "[traversal.noon] sun_elevation_deg"},
			 {"traversals = morning_low_sun", "traversals = dusk morning_low_sun", "'dusk' has no section"}})
	{
		const std::string cfg = tinyConfig(dir, from, to);
		std::string out;
		EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/out", &out), 0) << to;
		EXPECT_NE(out.find(msg), std::string::npos) << "expected '" << msg << "' in: " << out;
		EXPECT_EQ(filesIn(dir + "/out"), 0u) << to;
	}
}

// --end-s ends every traversal at its first frame at or past a route
// position, whatever its speed: the count the library computes, and the
// last frame within one frame's travel past the end.
TEST(SimApp, EndByDistance)
{
	const std::string dir = tempDir("sim_app_end");
	const std::string cfg = tinyConfig(dir);
	std::string out;
	ASSERT_EQ(runCommand(appPath() + " sim -c " + cfg + " -o " + dir + "/out --traversals noon,evening_warm "
							 "--start-s 100 --end-s 103.5",
				  &out),
		0)
		<< out;
	auto o = shadyloc::sim::TSimOptions::FromFile(cfg);
	shadyloc::sim::StereoSimulator sim(o);
	for (const std::string t : {"noon", "evening_warm"})
	{
		auto tr = o.traversal(t);
		tr.start_s_m = 100;
		tr.frames = 0;
		tr.end_s_m = 103.5;
		sim.setTraversal(tr);
		const int n = sim.frameCount();
		EXPECT_GE(sim.routePosition(n - 1), 103.5) << t;
		EXPECT_LT(sim.routePosition(n - 2), 103.5) << t;
		EXPECT_LT(sim.routePosition(n - 1) - 103.5, 1.2 * tr.speed_mps / o.camera.fps) << t;
		shadyloc::io::RawlogReader r(dir + "/out/" + t + ".rawlog");
		int frames = 0;
		while (r.next()) frames++;
		EXPECT_EQ(frames, n) << t;
		// The plan printed before rendering names the count and the stretch.
		EXPECT_NE(out.find(std::to_string(n) + " frames, route s = 100.0 .. "), std::string::npos) << out;
	}
	// A count and an end are alternatives; an end must lie ahead, within the scene.
	for (const auto& [args, msg] : std::vector<std::pair<std::string, std::string>>{
			 {"--frames 3 --end-s 120", "--frames and --end-s: give one, not both"},
			 {"--start-s 100 --end-s 90", "end_s_m must be > start_s_m"},
			 {"--end-s 320.5", "end_s_m = 320.5 lies past the end of the scene"}})
	{
		EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/bad " + args, &out), 0) << args;
		EXPECT_NE(out.find(msg), std::string::npos) << "expected '" << msg << "' in: " << out;
		EXPECT_EQ(filesIn(dir + "/bad"), 0u) << args;
	}
}

// In the .ini, `frames` and `end_s_m` are alternatives too.
TEST(SimApp, FramesOrEndInTheIni)
{
	const std::string dir = tempDir("sim_app_end_ini");
	for (const auto& [from, to, msg] : std::vector<std::tuple<std::string, std::string, std::string>>{
			 {"\nstart_s_m = 80\n", "\nstart_s_m = 80\nend_s_m = 120\n",
				 "[traversal.noon] end_s_m: give either frames (a count) or end_s_m (a route position), not both"},
			 {"\nframes = 3\n", "\nframes = 0\n", "[traversal.morning_low_sun] frames: must be >= 1 (or give end_s_m instead)"}})
	{
		const std::string cfg = tinyConfig(dir, from, to);
		std::string out;
		EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/out", &out), 0) << to;
		EXPECT_NE(out.find(msg), std::string::npos) << "expected '" << msg << "' in: " << out;
		EXPECT_EQ(filesIn(dir + "/out"), 0u) << to;
	}
	// An end too far past the route is refused.
	std::ifstream in(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	std::stringstream ss;
	ss << in.rdbuf();
	std::string s = ss.str();
	s = std::regex_replace(s, std::regex("\nend_s_m = 170[^\n]*"), "\nend_s_m = 321", std::regex_constants::format_first_only);
	std::ofstream(dir + "/past.ini") << s;
	std::string out;
	EXPECT_NE(runCommand(appPath() + " sim -q -c " + dir + "/past.ini -o " + dir + "/out", &out), 0);
	EXPECT_NE(out.find("[traversal.morning_low_sun] end_s_m = 321 lies past the end of the scene (at most 20 m past [sim.scene] "
						  "route_length_m = 300)"), std::string::npos)
		<< out;
}

TEST(SimApp, UnknownTraversalAndMissingConfig)
{
	const std::string dir = tempDir("sim_app_unknown");
	const std::string cfg = tinyConfig(dir);
	std::string out;
	EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/out --traversals noon,dusk", &out), 0);
	EXPECT_NE(out.find("unknown traversal 'dusk'"), std::string::npos) << out;
	EXPECT_EQ(filesIn(dir + "/out"), 0u) << "noon must not be rendered before the name check";
	EXPECT_NE(runCommand(appPath() + " sim -q -c " + dir + "/nope.ini -o " + dir + "/out", &out), 0);
	EXPECT_NE(out.find("nope.ini': simulator config file not found"), std::string::npos) << out;
}

TEST(SimApp, UnwritableOutputLeavesNothing)
{
	const std::string dir = tempDir("sim_app_unwritable");
	const std::string cfg = tinyConfig(dir);
	std::ofstream(dir + "/afile") << "x";  // a file where a directory is expected
	std::string out;
	EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/afile/out", &out), 0);
	EXPECT_NE(out.find("afile/out"), std::string::npos) << out;
	// A failure after every frame was rendered: the ground-truth path is
	// taken by a directory. Neither the rawlog nor any temporary is left.
	fs::create_directories(dir + "/late/noon.tum");
	EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/late --traversals noon", &out), 0);
	EXPECT_NE(out.find("noon.tum"), std::string::npos) << out;
	EXPECT_EQ(filesIn(dir + "/late"), 0u) << "partial output left behind";
	EXPECT_FALSE(fs::exists(dir + "/late/noon.rawlog"));
}

TEST(SimApp, ReadOnlyOutputDirectory)
{
	const std::string dir = tempDir("sim_app_readonly");
	const std::string cfg = tinyConfig(dir);
	std::string out;
	// An existing directory we cannot write into (skip when running as root,
	// which ignores permissions).
	fs::create_directories(dir + "/ro");
	fs::permissions(dir + "/ro", fs::perms::owner_read | fs::perms::owner_exec);
	if (std::ofstream(dir + "/ro/probe"))
	{
		fs::remove(dir + "/ro/probe");
		fs::permissions(dir + "/ro", fs::perms::owner_all);
		GTEST_SKIP() << "running with permission override (root): read-only case not testable";
	}
	EXPECT_NE(runCommand(appPath() + " sim -q -c " + cfg + " -o " + dir + "/ro --traversals noon", &out), 0);
	EXPECT_NE(out.find("ro/noon.rawlog"), std::string::npos) << out;
	fs::permissions(dir + "/ro", fs::perms::owner_all);
	EXPECT_EQ(filesIn(dir + "/ro"), 0u);
}
