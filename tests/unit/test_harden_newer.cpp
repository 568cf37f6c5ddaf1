/* Issue #23, "accepted silently, or a message that does not help": each case
 * as the newer commands see it. Every test here failed before its fix (run
 * against an older build with SHADYLOC_TEST_APP and LD_LIBRARY_PATH).
 *  - NewerChecks.*: synthetic data, fast (label cli; Settings.* unit);
 *  - NewerChecksSim.*: a map surveyed from two short simulator traversals
 *    (label slow cli). */
#include "../support/TestSupport.h"

#include <shadyloc/core/Settings.h>
#include <shadyloc/eval/RunList.h>
#include <shadyloc/features/StereoFeatures.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <fstream>
#include <sstream>

#include <sys/resource.h>
#include <sys/wait.h>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** The error of loading [features] from `ini`, "" if it loads. */
std::string featureError(const std::string& ini)
{
	try
	{
		features::TStereoFeatureOptions o;
		o.loadFromConfigFile(mrpt::config::CConfigFileMemory(ini), "features");
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
	return "";
}

/** The error of reading a run list, "(no error)" if it reads. */
std::string runListError(const std::string& path)
{
	try
	{
		eval::readRunList(path);
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
	return "(no error)";
}

/** Peak resident memory [kB] of `shadyloc args` (its exit status in *rc). */
long peakKbOfShell(const std::string& args, int* rc)
{
	const pid_t pid = fork();
	if (pid == 0)
	{
		const std::string cmd = "exec " + test::appPath() + " " + args + " >/dev/null 2>&1";
		execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
		_exit(127);
	}
	int status = 0;
	rusage ru{};
	wait4(pid, &status, 0, &ru);
	*rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
	return ru.ru_maxrss;
}
}  // namespace

// max_per_cell <= 0 meant "no limit" without a word; a BRIEF patch size of
// 0 was refused by the describer, naming neither key nor file.
TEST(Settings, FeatureCountsAndBriefPatchRefusedNamingTheKey)
{
	EXPECT_NE(featureError("[features]\nmax_per_cell = 0\n").find("[features] max_per_cell: must be >= 1"), std::string::npos)
		<< featureError("[features]\nmax_per_cell = 0\n");
	EXPECT_NE(featureError("[features]\nmax_per_cell_right = -1\n").find("max_per_cell_right: must be >= 1"), std::string::npos);
	EXPECT_NE(featureError("[features]\nbrief_patch_size_px = 0\n").find("[features] brief_patch_size_px: must be in [8, 250]"), std::string::npos)
		<< featureError("[features]\nbrief_patch_size_px = 0\n");
	EXPECT_EQ(featureError("[features]\nmax_per_cell = 1\nbrief_patch_size_px = 8\n"), "");
}

// The same rawlog twice in a run list was accepted (a run localised against
// its own map); a path with spaces was refused as "5 fields" with no hint.
TEST(EvalRunList, SameRawlogTwiceRefusedAndQuotedPathsWithSpaces)
{
	const std::string dir = test::tempDir("runlist_newer");
	fs::create_directories(dir + "/my runs");
	test::writeFileContents(dir + "/a.rawlog", "x");
	test::writeFileContents(dir + "/my runs/b.rawlog", "x");
	test::writeFileContents(dir + "/runs.txt", "a a.rawlog\nb ./a.rawlog\n");
	EXPECT_NE(
		runListError(dir + "/runs.txt").find("runs.txt:2: run 'b': rawlog '" + dir + "/a.rawlog' is run 'a''s (line 1)"),
		std::string::npos)
		<< runListError(dir + "/runs.txt");
	const std::string hint = "(a path with spaces must be in double quotes: \"my runs/a.rawlog\")";
	test::writeFileContents(dir + "/runs.txt", "a a.rawlog\nb my runs/b.rawlog gt.tum\n");
	EXPECT_NE(runListError(dir + "/runs.txt").find("runs.txt:2: 4 fields; a run is 'name rawlog [ground_truth.tum]' " + hint),
		std::string::npos)
		<< runListError(dir + "/runs.txt");
	test::writeFileContents(dir + "/runs.txt", "a a.rawlog\nb my runs/b.rawlog\n");
	EXPECT_NE(runListError(dir + "/runs.txt").find("runs.txt:2: run 'b': rawlog '" + dir + "/my' does not exist " + hint),
		std::string::npos)
		<< runListError(dir + "/runs.txt");
	test::writeFileContents(dir + "/runs.txt", "a a.rawlog\nb \"my runs/b.rawlog\"\n");
	ASSERT_EQ(runListError(dir + "/runs.txt"), "(no error)");
	EXPECT_EQ(eval::readRunList(dir + "/runs.txt")[1].rawlogPath, dir + "/my runs/b.rawlog");
}

TEST(NewerChecks, LocaliseConfigErrorNamesFileAndLine)
{
	const std::string dir = test::tempDir("newer_localise_cfg");
	fs::copy_file(test::sourcePath("tests/golden/CKeyframeMap.bin"), dir + "/map.kfmap");
	test::writeSyntheticRawlog(dir + "/live.rawlog", 2, false);
	test::writeFileContents(dir + "/typo.ini", "[localiser]\nmin_inliers = 12\nmin_inlier = 3\n");
	test::writeFileContents(dir + "/cells.ini", "; corners\n[features]\nmax_per_cell = 0\n");
	std::string out;
	const std::string base = test::appPath() + " localise -q -m " + dir + "/map.kfmap -i " + dir + "/live.rawlog -o " + dir + "/o -c " +
							 test::sourcePath("config/vo_sim.ini") + " -c " + test::sourcePath("config/localise_sim.ini");
	EXPECT_EQ(test::runCommand(base + " -c " + dir + "/typo.ini", &out), 1) << out;
	EXPECT_NE(out.find(dir + "/typo.ini:3: [localiser] min_inlier: unknown key"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(base + " -c " + dir + "/cells.ini", &out), 1) << out;
	EXPECT_NE(out.find(dir + "/cells.ini:3: [features] max_per_cell: must be >= 1"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/o"));
}

TEST(NewerChecks, CalibrateAlphaRefusesRunsOfTwoCamerasAndGammaWithoutGammaCurve)
{
	const std::string dir = test::tempDir("newer_calib");
	test::writeSyntheticRawlog(dir + "/a.rawlog", 2, false);
	test::writeSyntheticRawlog(dir + "/b.rawlog", 2, false);
	test::writeSyntheticRawlog(dir + "/wide.rawlog", 2, false, 200, 120);
	std::string out;
	const std::string base = test::appPath() + " calibrate-alpha --no-plot --bootstrap 0 --max-frames 2 -o " + dir + "/cam";
	EXPECT_EQ(test::runCommand(base + " --linearise none --runs " + dir + "/a.rawlog," + dir + "/wide.rawlog", &out), 1) << out;
	EXPECT_NE(out.find("the runs are of different cameras"), std::string::npos) << out;
	EXPECT_NE(out.find("200x120 px"), std::string::npos) << out;
	EXPECT_EQ(
		test::runCommand(
			base + " --linearise none --runs " + dir + "/a.rawlog," + dir + "/b.rawlog --runs " + dir + "/wide.rawlog," + dir + "/wide.rawlog",
			&out),
		1)
		<< out;
	EXPECT_NE(out.find("must be of one camera"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(base + " --linearise srgb --gamma 2 --runs " + dir + "/a.rawlog," + dir + "/b.rawlog", &out), 2) << out;
	EXPECT_NE(out.find("--gamma is used only with --linearise gamma"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/cam.ini"));
}

// A damaged map with a valid header was held twice in memory (the file's
// bytes and a copy) before it was refused.
TEST(NewerChecks, DamagedMapCostsItsSizeOnceInMemory)
{
	const std::string dir = test::tempDir("newer_map_memory");
	std::ifstream g(test::sourcePath("tests/golden/CKeyframeMap.bin"), std::ios::binary);
	std::string bytes((std::istreambuf_iterator<char>(g)), std::istreambuf_iterator<char>());
	int rc = 0;
	const long intact = peakKbOfShell("map-info " + test::sourcePath("tests/golden/CKeyframeMap.bin"), &rc);
	ASSERT_EQ(rc, 0);
	const size_t size = 150u << 20;
	{
		std::ofstream f(dir + "/big.kfmap", std::ios::binary);
		f << bytes.substr(0, 64);
		std::string junk(1 << 20, '\x5a');
		for (size_t n = 64; n < size; n += junk.size()) f << junk;
	}
	const long damaged = peakKbOfShell("map-info " + dir + "/big.kfmap", &rc);
	EXPECT_EQ(rc, 1);
	EXPECT_LT(damaged, intact + static_cast<long>(1.5 * (size >> 10)))
		<< "peak " << damaged << " kB, intact map " << intact << " kB, file " << (size >> 10) << " kB";
	fs::remove(dir + "/big.kfmap");
}

// The renderer named its own temporary output: "'.one.tmp-7799.png':
// nothing to draw".
TEST(NewerChecks, RenderOfOneKeyframeMapNamesTheMap)
{
	const std::string dir = test::tempDir("newer_render_one");
	std::string out;
	ASSERT_EQ(
		test::runCommand(
			test::appPath() + " sim -q -c " + test::sourcePath("config/sim.ini") + " -o " + dir + " --traversals noon --frames 1", &out),
		0)
		<< out;
	ASSERT_EQ(
		test::runCommand(
			test::appPath() + " survey -q -i " + dir + "/noon.rawlog -o " + dir + "/one.kfmap -c " + test::sourcePath("config/vo_sim.ini"), &out),
		0)
		<< out;
	EXPECT_EQ(test::runCommand(test::appPath() + " render -m " + dir + "/one.kfmap -o " + dir + "/one.png", &out), 1) << out;
	EXPECT_NE(out.find("keyframe map '" + dir + "/one.kfmap': a single keyframe"), std::string::npos) << out;
	EXPECT_EQ(out.find(".tmp-"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/one.png"));
}

// ---- with a map surveyed from the simulator --------------------------------
namespace
{
struct TSimData
{
	std::string dir, sim, noonMap, overcastMap, cfg;
};

/** noon and overcast, 8 frames each, and both surveyed into maps. */
const TSimData& simData()
{
	static const TSimData d = [] {
		TSimData t;
		t.dir = test::tempDir(std::string("newer_sim_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
		t.sim = t.dir + "/sim";
		t.cfg = " -c " + test::sourcePath("config/vo_sim.ini") + " -c " + test::sourcePath("config/localise_sim.ini");
		std::string out;
		if (test::runCommand(
				test::appPath() + " sim -q -c " + test::sourcePath("config/sim.ini") + " -o " + t.sim + " --traversals noon,overcast --frames 8",
				&out) != 0)
			throw std::runtime_error(out);
		for (const char* run : {"noon", "overcast"})
			if (test::runCommand(
					test::appPath() + " survey -q -i " + t.sim + "/" + run + ".rawlog -o " + t.dir + "/" + run + ".kfmap -c " +
						test::sourcePath("config/vo_sim.ini") + " --gt " + t.sim + "/" + run + ".tum",
					&out) != 0)
				throw std::runtime_error(out);
		t.noonMap = t.dir + "/noon.kfmap";
		t.overcastMap = t.dir + "/overcast.kfmap";
		return t;
	}();
	return d;
}

std::string localise(const TSimData& d, const std::string& map, const std::string& live, const std::string& out, const std::string& extra = "")
{
	std::string log;
	const int rc = test::runCommand(
		test::appPath() + " localise -q -m " + map + " -i " + d.sim + "/" + live + ".rawlog -o " + out + d.cfg + extra, &log);
	if (rc != 0) throw std::runtime_error(log);
	return out;
}
}  // namespace

// A live run of another camera localised to 0 fixes with exit 0.
TEST(NewerChecksSim, LocaliseRefusesALiveRunOfAnotherCamera)
{
	const auto& d = simData();
	test::writeSyntheticRawlog(d.dir + "/other_camera.rawlog", 3, false, 320, 240);
	std::string out;
	EXPECT_EQ(
		test::runCommand(
			test::appPath() + " localise -q -m " + d.noonMap + " -i " + d.dir + "/other_camera.rawlog -o " + d.dir + "/o" + d.cfg, &out),
		1)
		<< out;
	EXPECT_NE(out.find("live rawlog '" + d.dir + "/other_camera.rawlog' (camera 'CAMERA': 320x240 px"), std::string::npos) << out;
	EXPECT_NE(out.find("is not of the camera of map '" + d.noonMap + "' (512x384 px"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(d.dir + "/o"));
}

// render --localised drew a run over a map, or a ground truth, it never met.
TEST(NewerChecksSim, RenderLocalisedRefusesAnotherMapOrAnotherRunsTruth)
{
	const auto& d = simData();
	const std::string withGt = localise(d, d.noonMap, "overcast", d.dir + "/loc_gt", " --gt " + d.sim + "/overcast.tum");
	const std::string noGt = localise(d, d.noonMap, "overcast", d.dir + "/loc");
	std::string out;
	const std::string render = test::appPath() + " render -o " + d.dir + "/r.png --localised ";
	EXPECT_EQ(test::runCommand(render + noGt + " -m " + d.overcastMap, &out), 1) << out;
	EXPECT_NE(out.find("was localised against map"), std::string::npos) << out;
	EXPECT_NE(out.find("not against -m '" + d.overcastMap + "'"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(render + withGt + " -m " + d.noonMap + " --gt " + d.sim + "/noon.tum", &out), 1) << out;
	EXPECT_NE(out.find("--gt '" + d.sim + "/noon.tum' is not the ground truth"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(render + noGt + " -m " + d.noonMap + " --gt " + d.sim + "/noon.tum", &out), 1) << out;
	EXPECT_NE(out.find("shares no time with the run of --localised '" + noGt + "'"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(d.dir + "/r.png"));
	// The right ones still draw.
	EXPECT_EQ(test::runCommand(render + noGt + " -m " + d.noonMap + " --gt " + d.sim + "/overcast.tum", &out), 0) << out;
}

// figures labelled a pair with names that match nothing, and took a
// baseline and a combined run of different pairs as one.
TEST(NewerChecksSim, FiguresRefuseMismatchedRunsAndWarnOfNamesThatMatchNothing)
{
	const auto& d = simData();
	const std::string base = localise(d, d.noonMap, "overcast", d.dir + "/base", " --localisers mono");
	const std::string comb = localise(d, d.noonMap, "overcast", d.dir + "/comb");
	const std::string otherBase = localise(d, d.overcastMap, "noon", d.dir + "/obase", " --localisers mono");
	const std::string otherComb = localise(d, d.overcastMap, "noon", d.dir + "/ocomb");
	const std::string otherMap = localise(d, d.overcastMap, "overcast", d.dir + "/omap");  // the same live run
	fs::create_directories(d.dir + "/figs");
	const std::string figs = test::appPath() + " figures -o " + d.dir + "/figs";
	std::string out;
	EXPECT_EQ(test::runCommand(figs + " -p overcast,noon," + base + "," + otherMap, &out), 1) << out;
	EXPECT_NE(out.find("the baseline run used map '" + d.noonMap + "', the combined run map '" + d.overcastMap + "'"), std::string::npos)
		<< out;
	EXPECT_NE(out.find("not one pair"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(figs + " -p overcast,noon," + base + "," + comb + " -p overcast,x," + otherBase + "," + otherComb, &out), 1)
		<< out;
	EXPECT_NE(out.find("live run name 'overcast' is given to two different live runs"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(d.dir + "/figs/figure7.png"));
	EXPECT_EQ(test::runCommand(figs + " -p foo,bar," + base + "," + comb, &out), 0) << out;
	EXPECT_NE(out.find("warning: --pair 'foo,bar,"), std::string::npos) << out;
	EXPECT_NE(out.find("live run name 'foo' matches nothing"), std::string::npos) << out;
	EXPECT_NE(out.find("map name 'bar' matches nothing"), std::string::npos) << out;
}

// eval --merge merged the jobs of a damaged map with exit 0.
TEST(NewerChecksSim, EvalMergeRefusesADamagedMap)
{
	const auto& d = simData();
	test::writeFileContents(d.sim + "/runs.txt", "noon noon.rawlog noon.tum\novercast overcast.rawlog overcast.tum\n");
	const std::string o = d.dir + "/eval", eval = test::appPath() + " eval -q --runs " + d.sim + "/runs.txt -o " + o + d.cfg;
	std::string out;
	ASSERT_EQ(test::runCommand(eval, &out), 0) << out;
	const std::string map = o + "/jobs/map_overcast/map.kfmap";
	std::fstream f(map, std::ios::in | std::ios::out | std::ios::binary);
	f.seekp(static_cast<std::streamoff>(fs::file_size(map) / 2));
	f.put('\x00').put('\x01').put('\x02');
	f.close();
	fs::remove(o + "/table1.md");
	EXPECT_EQ(test::runCommand(eval + " --merge", &out), 1) << out;
	EXPECT_NE(out.find("job 1 (map of run 'overcast'): keyframe map '" + map + "'"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(o + "/table1.md"));
}
