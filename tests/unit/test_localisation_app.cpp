/* ShadyLoc tests: `shadyloc localise` as a program on a small simulated
 * dataset (config/sim.ini's noon and overcast traversals, 30 frames each: the
 * sim_sequences fixture under ctest, rendered here otherwise):
 *  - ground truth never leaks: the outputs are byte-identical with the ground
 *    truth stripped from the map (`map-info --strip-gt`), across three runs
 *    and across --threads 1 and 2;
 *  - bad input: a map with other descriptor parameters, a live run without
 *    the colour images its channels need, an empty map (errors, non-zero
 *    exit, nothing partial, an earlier OUTDIR untouched); a live run through
 *    another world (another scene seed): zero fixes;
 *  - a rawlog made by `shadyloc filter` (with or without its colour pairs)
 *    localises exactly as its colour original;
 *  - `--live`: the same frames as an image sequence through OpenCV's
 *    VideoCapture localise exactly as the rawlog does; bad live input. */
#include "../support/GifFrames.h"
#include "../support/Sequences.h"
#include "../support/TestSupport.h"

#include <shadyloc/io/Rawlog.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

namespace
{
using namespace shadyloc;
namespace fs = std::filesystem;

/** The dataset: noon and overcast rawlogs with ground truth, the noon map
 * surveyed from them (ground truth stored beside its keyframes). Made once
 * per process. */
struct TDataset
{
	std::string dir, noon, noonGt, overcast, overcastGt, map;
};

const TDataset& dataset()
{
	static const TDataset d = [] {
		TDataset t;
		// One folder per test: ctest runs the suite's tests as parallel
		// processes, and tempDir empties the folder it returns.
		t.dir = test::tempDir(
			std::string("localise_app_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
		std::string sim = test::fixtureDir().empty() ? "" : test::fixtureDir() + "/sim";
		if (sim.empty() || !fs::exists(sim + "/overcast.rawlog"))
		{
			sim = t.dir + "/sim";
			std::string out;
			const int rc = test::runCommand(
				test::appPath() + " sim -q -c " + test::sourcePath("config/sim.ini") + " -o " + sim +
					" --traversals noon,overcast --frames " + std::to_string(test::kSimFixtureFrames),
				&out);
			if (rc != 0) throw std::runtime_error("sim failed: " + out);
		}
		t.noon = sim + "/noon.rawlog";
		t.noonGt = sim + "/noon.tum";
		t.overcast = sim + "/overcast.rawlog";
		t.overcastGt = sim + "/overcast.tum";
		t.map = t.dir + "/noon.kfmap";
		std::string out;
		const int rc = test::runCommand(
			test::appPath() + " survey -q -i " + t.noon + " -o " + t.map + " -c " + test::sourcePath("config/vo_sim.ini") + " --gt " +
				t.noonGt,
			&out);
		if (rc != 0) throw std::runtime_error("survey failed: " + out);
		return t;
	}();
	return d;
}

std::string localiseCmd(const std::string& map, const std::string& live, const std::string& outDir, const std::string& extra = "")
{
	return test::appPath() + " localise -q -m " + map + " -i " + live + " -o " + outDir + " -c " +
		   test::sourcePath("config/vo_sim.ini") + " -c " + test::sourcePath("config/localise_sim.ini") + extra;
}

/** summary.json without the provenance's map entries (the map file's path
 * and hash, which name the input and so differ between two map files). */
std::string withoutMapProvenance(const std::string& summary)
{
	return std::regex_replace(summary, std::regex(R"("map": "[^"]*", "map_fnv1a64": "[0-9a-f]+")"), "\"map\": -");
}

int jsonInt(const std::string& json, const std::string& key)
{
	std::smatch m;
	if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([0-9]+)"))) return -1;
	return std::stoi(m[1]);
}

/** Nothing staged beside `dir` was left behind (".<name>.tmp-<pid>",
 * ".<name>.old-<pid>", or the older ".<name>.partial-<pid>"). */
void expectNoStagedLeftovers(const std::string& dir)
{
	for (const auto& e : fs::directory_iterator(fs::path(dir).parent_path()))
		for (const char* staged : {".partial", ".tmp-", ".old-"})
			EXPECT_EQ(e.path().filename().string().find(staged), std::string::npos) << e.path();
}

TEST(LocalisationApp, OutputsIdenticalWithoutGroundTruthAcrossRunsAndThreadCounts)
{
	const auto& d = dataset();
	// The map without its ground truth: a copy differing in that alone.
	const std::string stripped = d.dir + "/noon_nogt.kfmap";
	std::string out;
	ASSERT_EQ(test::runCommand(test::appPath() + " map-info " + d.map + " --strip-gt " + stripped, &out), 0) << out;
	{
		const auto a = CKeyframeMap::LoadFromFile(d.map), b = CKeyframeMap::LoadFromFile(stripped);
		ASSERT_GT(a->keyframeCount(), 5u);
		EXPECT_EQ(a->groundTruthCount(), a->keyframeCount());  // the survey stored it
		EXPECT_EQ(b->groundTruthCount(), 0u);
		ASSERT_EQ(a->keyframeCount(), b->keyframeCount());
		for (uint32_t i = 0; i < a->keyframeCount(); i++)
		{
			EXPECT_TRUE(a->keyframe(i).T_map_kf.matrix() == b->keyframe(i).T_map_kf.matrix()) << i;
			ASSERT_EQ(a->keyframe(i).channels.size(), b->keyframe(i).channels.size());
			for (size_t c = 0; c < a->keyframe(i).channels.size(); c++)
				EXPECT_EQ(a->keyframe(i).channels[c].size(), b->keyframe(i).channels[c].size());
		}
	}
	EXPECT_NE(test::fileContents(d.map), test::fileContents(stripped));
	// --strip-gt refuses to write over its input.
	EXPECT_NE(test::runCommand(test::appPath() + " map-info " + d.map + " --strip-gt " + d.map, &out), 0) << out;
	EXPECT_EQ(CKeyframeMap::LoadFromFile(d.map)->groundTruthCount(), CKeyframeMap::LoadFromFile(d.map)->keyframeCount());

	// Three runs with two threads, one with one thread, one on the stripped map.
	struct TRun
	{
		std::string name, map, extra;
	};
	const std::vector<TRun> runs = {
		{"a", d.map, " --threads 2"}, {"b", d.map, " --threads 2"}, {"c", d.map, " --threads 2"},
		{"t1", d.map, " --threads 1"}, {"nogt", stripped, " --threads 2"}};
	for (const auto& r : runs)
		ASSERT_EQ(test::runCommand(localiseCmd(r.map, d.overcast, d.dir + "/out_" + r.name, r.extra), &out), 0)
			<< r.name << ": " << out;
	const std::string ref = d.dir + "/out_a/";
	const std::string refSummary = test::fileContents(ref + "summary.json");
	// The comparison covers localised frames.
	EXPECT_GT(jsonInt(refSummary, "fixes"), 10) << refSummary;
	for (const auto& r : runs)
	{
		if (r.name == "a") continue;
		const std::string o = d.dir + "/out_" + r.name + "/";
		for (const char* f : {"frames.csv", "trajectory.tum"})
			EXPECT_TRUE(test::fileContents(o + f) == test::fileContents(ref + f)) << r.name << ": " << f << " differs";
		if (r.name == "nogt")
		{
			EXPECT_NE(test::fileContents(o + "summary.json"), refSummary);  // the map's hash names the other file ...
			EXPECT_EQ(withoutMapProvenance(test::fileContents(o + "summary.json")), withoutMapProvenance(refSummary));  // ... alone
		}
		else
			EXPECT_TRUE(test::fileContents(o + "summary.json") == refSummary) << r.name << ": summary.json differs";
	}
	EXPECT_NE(withoutMapProvenance(refSummary), refSummary);  // the filter above did remove something
}

TEST(LocalisationApp, ShippedSurveyConfigMeetsTheMapSizeGoal)
{
	// The map the localisers run on by default (config/vo_sim.ini's [map]:
	// 300 landmarks per keyframe, within 0.4 points of the coverage of every
	// landmark, docs/map.md) must stay under the localisation issue's aim of
	// 10 MB per km of survey per channel, with a tenth of margin: the four 90 m
	// maps of the default data measured 8.8-10.2 (mono) and 6.5-7.1
	// (invariant), this fixture's 10.29 / 10.27: a change that stores a tenth
	// more per landmark, or keeps more landmarks, crosses it.
	const auto m = CKeyframeMap::LoadFromFile(dataset().map);
	const double km = m->pathLength() / 1000;
	ASSERT_GT(km, 0.005) << "the fixture's survey is too short to measure a size per km";
	const auto sz = m->sizeReport();
	ASSERT_EQ(sz.channel_bytes.size(), 2u);
	for (size_t c = 0; c < 2; c++)
	{
		const double mbPerKm = sz.channel_bytes[c] / 1e6 / km;
		const double perKf = double(sz.channel_measurements[c]) / m->keyframeCount();
		std::printf("[map-size] channel %zu: %.2f MB/km, %.1f measurements/keyframe\n", c, mbPerKm, perKf);
		EXPECT_LT(mbPerKm, 11.0) << "channel " << c;
		EXPECT_LE(perKf, m->options.landmarks_per_keyframe);
		// The budget is used: a map that kept a handful would meet the goal
		// trivially. The invariant image has fewer corners than the budget
		// (about 230 a keyframe with every landmark kept): half of it there.
		EXPECT_GT(perKf, (c == 0 ? 0.8 : 0.5) * m->options.landmarks_per_keyframe) << "channel " << c;
	}
}

TEST(LocalisationApp, BadInputFailsCleanlyOrGivesNoFix)
{
	const auto& d = dataset();
	std::string out;
	// An earlier OUTDIR (its marker says so): a failed run leaves it as it was.
	const std::string outDir = d.dir + "/bad_out";
	fs::create_directories(outDir);
	test::writeFileContents(outDir + "/frames.csv", "earlier\n");
	test::writeFileContents(outDir + "/.shadyloc-output", "shadyloc localise output\n");
	const auto expectUntouched = [&](const std::string& what) {
		EXPECT_EQ(test::fileContents(outDir + "/frames.csv"), "earlier\n") << what;
		EXPECT_FALSE(fs::exists(outDir + "/summary.json")) << what;
		expectNoStagedLeftovers(outDir);
	};

	// 1. A map made with other descriptor parameters than the live run's:
	// the invariant channel's descriptor kind differs (the map's ORB, live
	// FAST + BRIEF). Refused, naming both kinds and both sets.
	{
		std::string ini = test::fileContents(test::sourcePath("config/vo_sim.ini"));
		const auto at = ini.find("[features.invariant]\n");
		ASSERT_NE(at, std::string::npos);
		const auto kind = ini.find("\ndescriptor = orb", at);
		ASSERT_NE(kind, std::string::npos) << "config/vo_sim.ini: the invariant channel is no longer ORB";
		ini.replace(kind, std::string("\ndescriptor = orb").size(), "\ndescriptor = brief");
		const std::string cfg = d.dir + "/vo_sim_brief.ini";
		test::writeFileContents(cfg, ini);
		const int rc = test::runCommand(
			test::appPath() + " localise -q -m " + d.map + " -i " + d.overcast + " -o " + outDir + " -c " + cfg + " -c " +
				test::sourcePath("config/localise_sim.ini"),
			&out);
		EXPECT_NE(rc, 0) << out;
		EXPECT_NE(out.find("invariant"), std::string::npos) << out;
		EXPECT_NE(out.find("descriptor: map orb, live brief"), std::string::npos) << out;
		EXPECT_NE(out.find(d.map), std::string::npos) << out;
		expectUntouched("other descriptor parameters");
	}

	// 2. A live run without the colour images its channels are made from:
	// a grey camera (the invariant channel needs colour).
	{
		const std::string grey = d.dir + "/grey.rawlog";
		{
			io::RawlogWriter w(grey);
			for (const auto& o : test::readStereoFrames(d.overcast))
			{
				auto g = mrpt::obs::CObservationStereoImages::Create(*o);
				g->imageLeft = o->imageLeft.grayscale();
				g->imageRight = o->imageRight.grayscale();
				w.write(*g);
			}
			w.commit();
		}
		const int rc = test::runCommand(localiseCmd(d.map, grey, outDir), &out);
		EXPECT_NE(rc, 0) << out;
		EXPECT_NE(out.find("colour"), std::string::npos) << out;
		EXPECT_NE(out.find("grey.rawlog"), std::string::npos) << out;
		expectUntouched("grey live run");
	}

	// 3. An empty map (set up, no keyframes).
	{
		const auto full = CKeyframeMap::LoadFromFile(d.map);
		auto empty = CKeyframeMap::Create();
		empty->setup(full->calibration(), full->imageWidth(), full->imageHeight(), full->channels());
		const std::string emptyPath = d.dir + "/empty.kfmap";
		empty->saveToFile(emptyPath);
		const int rc = test::runCommand(localiseCmd(emptyPath, d.overcast, outDir), &out);
		EXPECT_NE(rc, 0) << out;
		EXPECT_NE(out.find("no keyframes"), std::string::npos) << out;
		EXPECT_NE(out.find("empty.kfmap"), std::string::npos) << out;
		expectUntouched("empty map");
	}

	// 4. A live run through another world (the scene seed differs): no place
	// in common, so no fix; not an error.
	{
		std::string ini = test::fileContents(test::sourcePath("config/sim.ini"));
		const std::regex seed(R"((\n)seed = 7\b)");
		ASSERT_TRUE(std::regex_search(ini, seed)) << "config/sim.ini's scene seed moved";
		ini = std::regex_replace(ini, seed, "$1seed = 8", std::regex_constants::format_first_only);
		const std::string cfg = d.dir + "/sim_seed8.ini";
		test::writeFileContents(cfg, ini);
		const std::string other = d.dir + "/other";
		ASSERT_EQ(
			test::runCommand(
				test::appPath() + " sim -q -c " + cfg + " -o " + other + " --traversals overcast --frames 20", &out),
			0)
			<< out;
		const std::string o = d.dir + "/other_out";
		ASSERT_EQ(test::runCommand(localiseCmd(d.map, other + "/overcast.rawlog", o), &out), 0) << out;
		const std::string s = test::fileContents(o + "/summary.json");
		EXPECT_EQ(jsonInt(s, "frames"), 20) << s;
		EXPECT_EQ(jsonInt(s, "fixes"), 0) << s;
		EXPECT_GT(jsonInt(s, "global_searches"), 0) << s;
		std::istringstream csv(test::fileContents(o + "/frames.csv"));
		std::string line;
		std::getline(csv, line);
		int rows = 0;
		while (std::getline(csv, line))
		{
			rows++;
			EXPECT_NE(line.find(",none,"), std::string::npos) << line;
		}
		EXPECT_EQ(rows, 20);
	}
}

// A rawlog made by `shadyloc filter` localises with the same result as its
// colour original: its channels are read, not made, and are the same
// images. So does the same rawlog with its colour pairs dropped; one whose
// channels another filter made is refused, naming its filter record.
TEST(LocalisationApp, FilteredRawlogLocalisesAsItsColourOriginal)
{
	const auto& d = dataset();
	std::string out;
	const std::string filt = d.dir + "/overcast_filtered.rawlog";
	ASSERT_EQ(
		test::runCommand(
			test::appPath() + " filter -q -i " + d.overcast + " -o " + filt + " -c " + test::sourcePath("config/filters_sim.ini"), &out),
		0)
		<< out;
	const std::string greyOnly = d.dir + "/overcast_channels_only.rawlog";
	{
		// Every object but the colour pairs (the filter record stays).
		io::RawlogWriter w(greyOnly);
		io::RawlogReader r(filt);
		size_t dropped = 0;
		while (const auto obj = r.next())
			for (const auto& o : io::observationsIn(obj))
			{
				io::loadExternalImages(*o);
				if (o->sensorLabel == "CAMERA")
					dropped++;
				else
					w.write(*o);
			}
		ASSERT_EQ(dropped, size_t(test::kSimFixtureFrames));
		w.commit();
	}
	const std::string colourOut = d.dir + "/colour_out";
	ASSERT_EQ(test::runCommand(localiseCmd(d.map, d.overcast, colourOut, " --gt " + d.overcastGt), &out), 0) << out;
	ASSERT_GT(jsonInt(test::fileContents(colourOut + "/summary.json"), "fixes"), 0);
	for (const auto& live : {filt, greyOnly})
	{
		const std::string o = d.dir + "/" + fs::path(live).stem().string() + "_out";
		ASSERT_EQ(test::runCommand(localiseCmd(d.map, live, o, " --gt " + d.overcastGt), &out), 0) << out;
		for (const char* f : {"frames.csv", "solves.csv", "trajectory.tum"})
			EXPECT_EQ(test::fileContents(o + "/" + f), test::fileContents(colourOut + "/" + f)) << live << ": " << f;
	}

	// Channels another filter made: not what the map was checked against.
	std::string ini = test::fileContents(test::sourcePath("config/filters_sim.ini"));
	const auto at = ini.find("peak_wavelength_red_nm = 620");
	ASSERT_NE(at, std::string::npos) << "config/filters_sim.ini changed";
	ini.replace(at, std::string("peak_wavelength_red_nm = 620").size(), "peak_wavelength_red_nm = 640");
	test::writeFileContents(d.dir + "/filters_other.ini", ini);
	const std::string other = d.dir + "/overcast_other.rawlog";
	ASSERT_EQ(
		test::runCommand(
			test::appPath() + " filter -q -i " + d.overcast + " -o " + other + " -c " + d.dir + "/filters_other.ini", &out),
		0)
		<< out;
	const std::string refused = d.dir + "/refused_out";
	EXPECT_NE(test::runCommand(localiseCmd(d.map, other, refused), &out), 0) << out;
	EXPECT_NE(out.find("overcast_other.rawlog"), std::string::npos) << out;
	EXPECT_NE(out.find("filter record"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(refused));
}

/** The rows of a table's text without one column (by 0-based index). */
std::string withoutColumn(const std::string& text, size_t column, char sep = ',')
{
	std::istringstream in(text);
	std::string line, out;
	while (std::getline(in, line))
	{
		std::vector<std::string> cells;
		std::stringstream ls(line);
		for (std::string c; std::getline(ls, c, sep);) cells.push_back(c);
		if (column < cells.size()) cells.erase(cells.begin() + long(column));
		for (size_t i = 0; i < cells.size(); i++) out += (i ? std::string(1, sep) : std::string()) + cells[i];
		out += "\n";
	}
	return out;
}

/** The rawlog's colour frames as a side-by-side PNG sequence (left | right)
 * and its calibration as `import folder`'s .ini. Returns the frame rate. */
double writeSideBySide(const std::string& rawlog, const std::string& dir, const std::string& calibIni)
{
	fs::create_directories(dir);
	io::RawlogReader r(rawlog);
	std::vector<double> stamps;
	while (const auto obj = r.next())
		for (const auto& o : io::observationsIn(obj))
		{
			const auto st = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(o);
			if (!st || st->sensorLabel != "CAMERA") continue;
			io::loadExternalImages(*st);
			cv::Mat both;
			cv::hconcat(st->imageLeft.asCvMatRef(), st->imageRight.asCvMatRef(), both);
			char name[32];
			std::snprintf(name, sizeof(name), "/%06zu.png", stamps.size());
			if (!cv::imwrite(dir + name, both)) throw std::runtime_error("cannot write " + dir + name);
			if (stamps.empty())
			{
				const auto& L = st->leftCamera;
				const auto& R = st->rightCamera;
				std::ostringstream ini;
				ini.precision(17);
				ini << "[left]\nfx_px = " << L.fx() << "\nfy_px = " << L.fy() << "\ncx_px = " << L.cx() << "\ncy_px = " << L.cy()
					<< "\n[right]\nfx_px = " << R.fx() << "\nfy_px = " << R.fy() << "\ncx_px = " << R.cx() << "\ncy_px = " << R.cy()
					<< "\n[stereo]\nbaseline_m = " << st->rightCameraPose.x() << "\nwidth_px = " << L.ncols
					<< "\nheight_px = " << L.nrows << "\n";
				test::writeFileContents(calibIni, ini.str());
			}
			stamps.push_back(mrpt::Clock::toDouble(st->timestamp));
		}
	if (stamps.size() < 2) throw std::runtime_error(rawlog + ": fewer than two frames");
	return double(stamps.size() - 1) / (stamps.back() - stamps.front());
}

}  // namespace

// The live path: the overcast run's frames as an image sequence read by
// OpenCV's VideoCapture (side by side, a calibration .ini) localise exactly as
// the rawlog does, frame for frame (the timestamps are the sequence's own,
// i / fps); every frame of a file is read, none dropped. Bad live input is
// refused naming it, with nothing written.
TEST(LocalisationApp, LiveImageSequenceLocalisesAsTheRawlog)
{
	const auto& d = dataset();
	std::string out;
	const std::string seq = d.dir + "/live_seq", calib = d.dir + "/live_calib.ini";
	const double fps = writeSideBySide(d.overcast, seq, calib);
	const std::string fromRawlog = d.dir + "/live_rawlog_out", fromLive = d.dir + "/live_out";
	ASSERT_EQ(test::runCommand(localiseCmd(d.map, d.overcast, fromRawlog), &out), 0) << out;
	const auto liveCmd = [&](const std::string& source, const std::string& calibIni) {
		return test::appPath() + " localise -q -m " + d.map + " --live " + source + " --camera " + calibIni + " --fps " +
			   std::to_string(fps) + " -c " + test::sourcePath("config/vo_sim.ini") + " -c " + test::sourcePath("config/localise_sim.ini");
	};
	ASSERT_EQ(test::runCommand(liveCmd(seq + "/%06d.png", calib) + " --view 10 -o " + fromLive, &out), 0) << out;
	// --view 10: a picture of the map and the path so far at frames 0, 10, 20.
	for (const char* f : {"frame_000000.png", "frame_000010.png", "frame_000020.png"})
	{
		const cv::Mat png = cv::imread(fromLive + "/view/" + f);
		EXPECT_EQ(png.cols, 800) << f;
		EXPECT_EQ(png.rows, 600) << f;
	}
	EXPECT_FALSE(fs::exists(fromLive + "/view/frame_000001.png"));
	const std::string a = test::fileContents(fromRawlog + "/frames.csv"), b = test::fileContents(fromLive + "/frames.csv");
	ASSERT_GT(jsonInt(test::fileContents(fromRawlog + "/summary.json"), "fixes"), 20);
	EXPECT_EQ(withoutColumn(b, 1), withoutColumn(a, 1)) << "frames.csv but the stamp column";
	EXPECT_EQ(
		withoutColumn(test::fileContents(fromLive + "/trajectory.tum"), 0, ' '),
		withoutColumn(test::fileContents(fromRawlog + "/trajectory.tum"), 0, ' '));
	const std::string summary = test::fileContents(fromLive + "/summary.json");
	EXPECT_EQ(jsonInt(summary, "frames_read"), test::kSimFixtureFrames) << summary;
	EXPECT_EQ(jsonInt(summary, "frames_dropped"), 0) << summary;

	// Bad input: no calibration; a calibration of another image size (the
	// frame is named); a source that does not open. Nothing is written.
	const std::string bad = d.dir + "/live_bad_out";
	EXPECT_NE(test::runCommand(test::appPath() + " localise -q -m " + d.map + " --live " + seq + "/%06d.png -o " + bad, &out), 0);
	EXPECT_NE(out.find("--camera"), std::string::npos) << out;
	std::string other = test::fileContents(calib);
	const auto at = other.find("width_px = ");
	ASSERT_NE(at, std::string::npos);
	other.insert(at + std::string("width_px = ").size(), "1");	// another width
	test::writeFileContents(d.dir + "/live_calib_other.ini", other);
	EXPECT_NE(test::runCommand(liveCmd(seq + "/%06d.png", d.dir + "/live_calib_other.ini") + " -o " + bad, &out), 0);
	EXPECT_NE(out.find("frame 0"), std::string::npos) << out;
	EXPECT_NE(out.find("side by side"), std::string::npos) << out;
	EXPECT_NE(test::runCommand(liveCmd(d.dir + "/missing/%06d.png", calib) + " -o " + bad, &out), 0);
	EXPECT_NE(out.find("cannot open"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(bad));
}

// -o replaces a folder only if it is an earlier localise output (or empty):
// a folder of the user's files, or one holding the run's own inputs, is
// refused by name with nothing deleted.
TEST(LocalisationApp, OutputFolderReplacedOnlyIfAnEarlierLocaliseOutput)
{
	const auto& d = dataset();
	std::string out;
	// A folder of unrelated files.
	const std::string mine = d.dir + "/mine";
	fs::create_directories(mine);
	test::writeFileContents(mine + "/notes.txt", "mine\n");
	EXPECT_NE(test::runCommand(localiseCmd(d.map, d.overcast, mine), &out), 0) << out;
	EXPECT_NE(out.find("'" + mine + "'"), std::string::npos) << out;
	EXPECT_EQ(test::fileContents(mine + "/notes.txt"), "mine\n");
	EXPECT_FALSE(fs::exists(mine + "/frames.csv"));
	expectNoStagedLeftovers(mine);

	// The folder that holds the map, the live rawlog and its ground truth.
	const std::string inputs = d.dir + "/inputs";
	fs::create_directories(inputs);
	for (const auto& f : {d.map, d.overcast, d.overcastGt}) fs::copy_file(f, inputs + "/" + fs::path(f).filename().string());
	const std::string map = inputs + "/noon.kfmap", live = inputs + "/overcast.rawlog", gt = inputs + "/overcast.tum";
	EXPECT_NE(test::runCommand(localiseCmd(map, live, inputs, " --gt " + gt), &out), 0) << out;
	EXPECT_NE(out.find(inputs), std::string::npos) << out;
	for (const auto& f : {map, live, gt}) EXPECT_TRUE(fs::is_regular_file(f)) << f << " deleted: " << out;

	// An earlier localise output is replaced; so is an empty folder.
	const std::string again = d.dir + "/again";
	fs::create_directories(again);
	ASSERT_EQ(test::runCommand(localiseCmd(d.map, d.overcast, again), &out), 0) << out;
	EXPECT_TRUE(fs::is_regular_file(again + "/frames.csv"));
	test::writeFileContents(again + "/stale.txt", "from before\n");
	ASSERT_EQ(test::runCommand(localiseCmd(d.map, d.overcast, again), &out), 0) << out;
	EXPECT_FALSE(fs::exists(again + "/stale.txt"));
	EXPECT_TRUE(fs::is_regular_file(again + "/summary.json"));
	expectNoStagedLeftovers(again);
}

/** Pixels of exactly this BGR colour in `img`. */
int countColourPixels(const cv::Mat& img, const cv::Vec3b& bgr)
{
	int n = 0;
	for (auto it = img.begin<cv::Vec3b>(); it != img.end<cv::Vec3b>(); ++it) n += *it == bgr;
	return n;
}

// --gif and --view N --view-images (issue #25, "Watch it"): the animation
// decodes through giflib with one frame per --gif-every frames, of the
// layout's size (two channel panels at the camera's aspect over a top-down
// view a third as tall as wide), with inlier matches drawn; the stills are
// the same pictures; the run's results are those of a run without pictures.
TEST(LocalisationApp, GifAndStillsOfTheRun)
{
	const auto& d = dataset();
	const std::string plain = d.dir + "/pictures_plain", withPictures = d.dir + "/pictures_out", gif = d.dir + "/run.gif";
	std::string out;
	ASSERT_EQ(test::runCommand(localiseCmd(d.map, d.overcast, plain), &out), 0) << out;
	ASSERT_EQ(
		test::runCommand(
			localiseCmd(d.map, d.overcast, withPictures, " --gif " + gif + " --gif-every 3 --frame-width 320 --view 10 --view-images"),
			&out),
		0)
		<< out;
	EXPECT_EQ(test::fileContents(withPictures + "/frames.csv"), test::fileContents(plain + "/frames.csv"));
	const auto g = test::decodeGif(gif);
	EXPECT_EQ(g.frames.size(), size_t((test::kSimFixtureFrames + 2) / 3)) << out;
	EXPECT_EQ(g.width, 320);
	EXPECT_EQ(g.height, 120 + 107);
	EXPECT_TRUE(g.loops);
	EXPECT_EQ(g.delays.front(), 13);  // 8 frames per second
	// The last frame's channel panels (the top 120 rows) show inliers.
	const cv::Vec3b inlierGreen(0, 204, 0);
	EXPECT_GT(countColourPixels(g.frames.back()(cv::Rect(0, 0, 160, 120)), inlierGreen), 20);
	EXPECT_GT(countColourPixels(g.frames.back()(cv::Rect(160, 0, 160, 120)), inlierGreen), 20);
	for (const char* f : {"frame_000000.png", "frame_000010.png", "frame_000020.png"})
	{
		const cv::Mat png = cv::imread(withPictures + "/view/" + f);
		EXPECT_EQ(png.cols, 320) << f;
		EXPECT_EQ(png.rows, 227) << f;
	}
	EXPECT_FALSE(fs::exists(withPictures + "/view/frame_000001.png"));
	expectNoStagedLeftovers(gif);
}
