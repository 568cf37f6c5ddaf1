/* ShadyLoc tests: the evaluation's output files byte for byte. A synthetic
 * localised run (no VO, no localiser: only what the writers read) goes
 * through the evaluation and localise's writers, and synthetic job records
 * of a three-run leave-one-out evaluation through the merge; every text file
 * they write is compared with tests/golden/eval/. The files are formats that
 * other programs read and that results are compared by, so a change in any
 * byte (a number's decimals, a space in the JSON) is a decision, not an
 * accident. After a deliberate change, regenerate and review:
 *
 *   SHADYLOC_UPDATE_GOLDEN=1 build/tests/shadyloc_tests --gtest_filter='EvalIdentity.*'
 *   git diff tests/golden/eval
 */
#include "../support/TestSupport.h"

#include <shadyloc/eval/Evaluation.h>
#include <shadyloc/eval/LeaveOneOut.h>
#include <shadyloc/eval/LocaliseOutputs.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using namespace shadyloc;
using namespace shadyloc::localisation;
using namespace shadyloc::eval;

namespace
{
const std::string kEvalGoldenDir = test::sourcePath("tests/golden/eval");

/** Writes the file, its folders made first. */
void writeFileMakingDirs(const std::string& path, const std::string& text)
{
	fs::create_directories(fs::path(path).parent_path());
	test::writeFileContents(path, text);
}

/** Compares the file `produced` with golden `name`, or rewrites the golden file when asked. */
void checkEvalGolden(const std::string& name, const std::string& produced)
{
	const std::string path = kEvalGoldenDir + "/" + name, actual = test::fileContents(produced);
	ASSERT_FALSE(actual.empty()) << produced << " is missing or empty";
	if (test::updatingGolden())
	{
		writeFileMakingDirs(path, actual);
		ADD_FAILURE() << "rewrote " << path << " (SHADYLOC_UPDATE_GOLDEN is set): review `git diff tests/golden/eval`";
		return;
	}
	const std::string golden = test::fileContents(path);
	ASSERT_FALSE(golden.empty()) << "golden file " << path << " is missing or empty";
	if (golden == actual) return;
	size_t at = 0;
	while (at < golden.size() && at < actual.size() && golden[at] == actual[at]) at++;
	ADD_FAILURE() << name << " differs from its golden file at byte " << at << ":\n  golden: "
				  << golden.substr(at >= 40 ? at - 40 : 0, 100) << "\n  actual: " << actual.substr(at >= 40 ? at - 40 : 0, 100);
}

Eigen::Isometry3d planarPose(double x, double y, double yawDeg)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.translation() = Eigen::Vector3d(x, y, 0);
	T.linear() = Eigen::AngleAxisd(yawDeg * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
	return T;
}

/** The ground truth's world frame is the map frame moved by this. */
const Eigen::Isometry3d kWorld = planarPose(100, 50, 10);

/** Six keyframes 2 m apart along x (camera z forward: a yaw turns it),
 * with their ground truth, of survey run "survey_a". */
CKeyframeMap::Ptr syntheticMap()
{
	auto map = CKeyframeMap::Create();
	geometry::TStereoCalib cal;
	map::TChannelParams mono, inv;
	mono.label = "mono";
	mono.filter_class = "shadyloc::CFilterMonochrome";
	inv.label = "invariant";
	inv.filter_class = "shadyloc::CFilterInvariant";
	map->setup(cal, 640, 480, {mono, inv});
	map->addRun("survey_a");
	for (int k = 0; k < 6; k++)
	{
		map::TMapKeyframe kf;
		kf.frame = 10 * k;
		kf.timestamp = 50 + k;
		kf.T_map_kf = planarPose(2.0 * k, 0, 0);
		kf.T_gt_kf = kWorld * kf.T_map_kf;
		kf.channels.resize(2);
		map->appendKeyframe(kf);
	}
	return map;
}

/** A localiser's result on frame i: solved or not, accepted or not, its pose
 * against keyframe kf (`off` metres from the truth along x). */
TLocaliserResult result(const std::string& ch, int i, bool solved, bool accepted, uint32_t kf, const Eigen::Isometry3d& T_kf_live)
{
	TLocaliserResult r;
	r.frame = static_cast<size_t>(i);
	r.channel = ch;
	r.solved = solved;
	r.status = accepted ? LocaliserStatus::Ok : (solved ? LocaliserStatus::FewInliers : LocaliserStatus::NoPrediction);
	r.kf_id = kf;
	r.T_kf_live = T_kf_live;
	r.cov = geometry::Matrix6d::Identity() * 1e-4;
	r.matches = 40 + i;
	r.warped = i % 4;
	r.patch_matches = i % 3;
	r.inliers = 25 + i;
	r.rms_px = 0.4 + 0.013 * i;
	r.var_factor = 0.9 + 0.021 * i;
	r.sigma_m = 0.02 + 0.0017 * i;
	r.sigma_deg = 0.1 + 0.011 * i;
	r.prediction_d2 = solved ? 1.5 + 0.25 * i : -1;
	r.motion_d2 = solved ? 0.75 + 0.125 * i : -1;
	r.consistent = i % 5;
	r.gate.median_axis_px = 3.25 + 0.5 * i;
	r.ms = 4.0 + 0.37 * i + (ch == "invariant" ? 1.1 : 0);
	return r;
}

/** 24 frames 0.5 m apart along x, then past the map's end: a global search
 * first, mono fixes, a blind stretch, invariant fixes (one false; the
 * baseline, mono alone, has none), a blind end; the oracle probed; the
 * fallback VO measuring some steps. */
std::vector<TLocalisationUpdate> syntheticRun(const CKeyframeMap& map, io::Trajectory& gt, bool combined = true)
{
	std::vector<TLocalisationUpdate> ups;
	gt.clear();
	for (int i = 0; i < 24; i++)
	{
		const double x = 0.5 * i + (i >= 20 ? 6.0 : 0.0);
		const Eigen::Isometry3d T_map_live = planarPose(x, 0.05 * std::sin(i), 0.3 * i);
		gt.push_back({100.0 + 0.1 * i, kWorld * T_map_live});
		const uint32_t kf = static_cast<uint32_t>(std::min(5.0, std::round(x / 2)));
		const Eigen::Isometry3d truth = map.keyframe(kf).T_map_kf.inverse() * T_map_live;
		Eigen::Isometry3d fix = truth;
		fix.translation().x() += i == 17 ? 1.0 : 0.004 * i;	 // frame 17: a false fix
		TLocalisationUpdate u;
		u.frame = static_cast<size_t>(i);
		u.timestamp = 100.0 + 0.1 * i;
		u.distance_m = 0.52 * i;
		u.frames_since_fix = i;
		u.global_search = i < 3;
		u.place.inliers = 30 + i;
		u.place.runner_up_inliers = 5 + i;
		u.motion_from = i == 0 ? "" : (i % 7 == 0 ? "invariant" : "mono");
		u.track_confirmed = i % 2 == 1;
		const bool monoFix = i >= 3 && i <= 8, invFix = combined && i >= 15 && i <= 20;
		u.localisers.push_back(result("mono", i, monoFix || i % 3 == 0, monoFix, kf, fix));
		if (combined) u.localisers.push_back(result("invariant", i, invFix || i % 4 == 1, invFix, kf, fix));
		if (monoFix || invFix)
		{
			u.used = monoFix ? "mono" : "invariant";
			u.kf_id = kf;
			u.kf_frame = map.keyframe(kf).frame;
			u.kf_stamp = map.keyframe(kf).timestamp;
			u.T_kf_live = fix;
		}
		u.placeKnown = i >= 3;
		u.T_map_live = T_map_live;
		u.oracle = {int8_t(i % 3 == 0), int8_t(i % 2 == 0 ? 1 : (i % 5 == 0 ? -1 : 0))};
		u.oracle.resize(u.localisers.size());
		u.ms_total = 20.0 + 1.37 * i;
		u.vo.ms.total = 8.0 + 0.29 * i;
		ups.push_back(u);
	}
	return ups;
}

TLocaliseProvenance provenance(bool withGt)
{
	TLocaliseProvenance p;
	p.buildCommit = "0123abc-dirty";
	p.configWhat = "vo \"sim\".ini + localise\\sim.ini";
	p.configText = "[localise]\nthreads = 3\n";
	p.mapPath = "maps/survey_a.kfmap";
	p.mapHash = "00000000000000aa";
	p.livePath = "live/run b.rawlog";
	p.liveHash = "00000000000000bb";
	if (withGt)
	{
		p.gtPath = "live/run b.tum";
		p.gtHash = "00000000000000cc";
	}
	p.startKf = withGt ? -1 : 2;
	return p;
}

/** localise's five files of the synthetic run, with or without ground truth, into dir. */
void writeSyntheticOutputs(const std::string& dir, bool withGt)
{
	const auto map = syntheticMap();
	io::Trajectory gt;
	const auto ups = syntheticRun(*map, gt);
	const TEvaluation ev = evaluate(ups, *map, withGt ? &gt : nullptr);
	TSystemOptions sys;
	sys.threads = 3;
	fs::create_directories(dir);
	writeLocaliseOutputs(dir, ups, ev, *map, sys, provenance(withGt));
}

// ---- a leave-one-out evaluation's job outputs ---------------------------------------------------
/** pair.tsv of pair job k: numbers varied by k, consistent with each other
 * (the merge checks them), ground truth where both runs have it. */
std::string variedPairRecord(const std::string& live, const std::string& map, const std::string& sys, size_t k, bool gt)
{
	const size_t frames = 40 + k, inMap = 30 + k % 5, fixes = 20 + k % 7, fixesInMap = std::min(fixes, inMap) - 2;
	const size_t trueFixes = gt ? fixes - 3 : 0, trueInMap = gt ? fixesInMap - 3 : 0;
	const bool combined = sys == "combined";
	const double between1 = 3.25 + 0.5 * k, between2 = k % 3 == 0 ? 120.0 + k : 40.5 + k, atEnd = 2.0;
	const double before = k % 2 ? 1.5 : 0.0;
	std::ostringstream s;
	s << "# shadyloc eval pair v1\nlive\t" << live << "\nmap\t" << map << "\nsystem\t" << sys << "\nlocalisers\t"
	  << (combined ? "mono,invariant" : "mono") << "\nframes\t" << frames << "\nground_truth\t" << int(gt)
	  << "\nin_map_frames\t" << inMap << "\nfixes\t" << fixes << "\nfixes_in_map\t" << fixesInMap << "\ntrue_fixes\t"
	  << trueFixes << "\ntrue_fixes_in_map\t" << trueInMap << "\nfalse_fixes\t" << (gt ? 2 : 0) << "\nunverifiable\t"
	  << (gt ? 1 : 0) << "\ntotal_m\t" << 30.5 + 1.25 * k << "\nblind_m\t" << between1 + between2 + atEnd + before
	  << "\nbefore_first_fix_m\t" << before << "\nfirst_fix_frame\t" << (k % 2 ? 2 : 0) << "\nglobal_searches\t" << k % 3
	  << "\n";
	s << "channel\tmono\t" << fixes << '\t' << (combined ? fixes - 5 : fixes) << '\t' << fixesInMap << '\t' << trueFixes
	  << '\t' << trueInMap << '\t' << (gt ? 2 : 0) << '\t' << (gt ? 1 : 0) << "\n";
	if (combined)
		s << "channel\tinvariant\t" << 10 + k % 4 << "\t5\t8\t" << (gt ? 7 : 0) << '\t' << (gt ? 6 : 0) << '\t'
		  << (gt ? 1 : 0) << "\t0\n";
	s << "bins\t" << (gt ? 10 : 0) << '\t' << (gt ? 15 : 0) << '\t' << trueInMap << "\n";
	if (gt)
		for (size_t e = 0; e < 3; e++) s << "fix_error\t" << 0.1 + 0.01 * k + 0.2 * e << '\t' << 0.5 + 0.75 * e << "\n";
	if (before > 0) s << "episode\tbefore_first_fix\t" << before << "\n";
	s << "episode\tbetween\t" << between1 << "\nepisode\tbetween\t" << between2 << "\nepisode\tat_end\t" << atEnd
	  << "\nend\n";
	return s.str();
}

/** The runs of `runList` (of runs a, b, c, with or without their ground
 * truth) and every job's output, as the jobs leave them; one job without
 * its job_timing.json. */
std::vector<eval::TEvalJob> writeJobOutputs(const std::string& dir, const std::string& runList, eval::TEvalInputs& in)
{
	for (const std::string r : {"a", "b", "c"})
	{
		writeFileMakingDirs(dir + "/data/" + r + ".rawlog", "rawlog of " + r);
		writeFileMakingDirs(dir + "/data/" + r + ".tum", "100 0 0 0 0 0 0 1 # " + r + "\n");
	}
	writeFileMakingDirs(dir + "/data/runs.txt", runList);
	in = eval::TEvalInputs::Load(dir + "/data/runs.txt", {}, false);
	const auto jobs = eval::makePlan(in.runs);
	const std::string jobsDir = dir + "/out/jobs/";
	const auto map = syntheticMap();
	io::Trajectory gt;
	const std::vector<TLocalisationUpdate> ups[2] = {syntheticRun(*map, gt, false), syntheticRun(*map, gt)};
	const TEvaluation evGt[2] = {evaluate(ups[0], *map, &gt), evaluate(ups[1], *map, &gt)};
	const TEvaluation evNone[2] = {evaluate(ups[0], *map, nullptr), evaluate(ups[1], *map, nullptr)};
	for (const auto& j : jobs)
	{
		const std::string d = jobsDir + j.name;
		fs::create_directories(d);
		if (j.index != 4)  // as a job writes it (seconds, 3 decimals)
		{
			char wall[32];
			std::snprintf(wall, sizeof wall, "%.3f", 1.5 + 0.25 * static_cast<double>(j.index));
			writeFileMakingDirs(d + "/job_timing.json",
					  std::string("{\"format\": \"shadyloc eval job timing\", \"version\": 1, \"wall_s\": ") + wall + "}\n");
		}
		if (j.isMap)
		{
			map->saveToFile(d + "/map.kfmap");
			writeFileMakingDirs(d + "/map.tsv", "# shadyloc eval map v1\nrun\t" + in.runs[j.run].name + "\nframes\t" +
										  std::to_string(60 + j.run) + "\nkeyframes\t6\ngt_keyframes\t6\nbreaks\t" +
										  std::to_string(j.run % 2) + "\npath_m\t10.25\n");
			continue;
		}
		const bool withGt = in.runs[j.run].hasGt() && in.runs[j.map].hasGt();
		const int s = j.system == eval::EvalSystem::Combined;
		writeFramesCsv(d + "/frames.csv", ups[s], withGt ? evGt[s] : evNone[s], *map);
		writeFileMakingDirs(d + "/summary.json", "{}\n");
		writeFileMakingDirs(d + "/trajectory.tum", "# " + j.name + "\n");
		writeFileMakingDirs(d + "/pair.tsv",
			variedPairRecord(in.runs[j.run].name, in.runs[j.map].name, eval::toString(j.system), j.index, withGt));
	}
	return jobs;
}
}  // namespace

TEST(EvalIdentity, LocaliseOutputsWithGroundTruth)
{
	const std::string dir = test::tempDir("eval_identity_gt");
	writeSyntheticOutputs(dir, true);
	for (const char* f : {"frames.csv", "solves.csv", "trajectory.tum", "summary.json", "timing.json"})
		checkEvalGolden(std::string("localise_gt/") + f, dir + "/" + f);
}

TEST(EvalIdentity, LocaliseOutputsWithoutGroundTruth)
{
	const std::string dir = test::tempDir("eval_identity_nogt");
	writeSyntheticOutputs(dir, false);
	for (const char* f : {"frames.csv", "solves.csv", "trajectory.tum", "summary.json", "timing.json"})
		checkEvalGolden(std::string("localise_nogt/") + f, dir + "/" + f);
}

/** Merges the job outputs of `runList` and compares the results with golden folder `golden`. */
void checkMerge(const std::string& golden, const std::string& runList)
{
	const std::string dir = test::tempDir("eval_identity_" + golden);
	eval::TEvalInputs in;
	const auto jobs = writeJobOutputs(dir, runList, in);
	in.buildCommit = "0123abc";
	eval::merge(dir + "/out", in, jobs, 12.5);
	for (const char* f : {"table1.md", "table1.csv", "summary.md", "eval.json", "timing.json", "figures_inputs.tsv"})
		checkEvalGolden(golden + "/" + f, dir + "/out/" + f);
	EXPECT_TRUE(fs::exists(dir + "/out/figures/figure9.png"));
}

TEST(EvalIdentity, MergeOutputsGroundTruthWhereGiven)
{
	checkMerge("merge", "a a.rawlog a.tum\nb b.rawlog b.tum\nc c.rawlog\n");
}

TEST(EvalIdentity, MergeOutputsWithGroundTruth)
{
	checkMerge("merge_gt", "# both with ground truth\na a.rawlog a.tum\nb b.rawlog b.tum\n");
}

TEST(EvalIdentity, MergeOutputsWithoutGroundTruth)
{
	checkMerge("merge_nogt", "b b.rawlog\nc c.rawlog\n");
}

TEST(EvalIdentity, JsonOutputsAreJsonAndKeepEveryString)
{
	// Every golden JSON file parses (a parser of the tests' own).
	size_t files = 0;
	for (const auto& f : fs::recursive_directory_iterator(kEvalGoldenDir))
		if (f.path().extension() == ".json")
		{
			files++;
			const auto doc = nlohmann::json::parse(test::fileContents(f.path().string()), nullptr, false);
			EXPECT_FALSE(doc.is_discarded()) << f.path();
			EXPECT_TRUE(doc.is_object() && doc.contains("format")) << f.path();
		}
	EXPECT_EQ(files, 10u);  // summary and timing of localise twice, eval and timing of the merge thrice

	// Strings that need escaping come back as they were: quotes, backslashes,
	// control characters, UTF-8.
	const auto map = syntheticMap();
	io::Trajectory gt;
	const auto ups = syntheticRun(*map, gt);
	const TEvaluation ev = evaluate(ups, *map, &gt);
	TLocaliseProvenance prov = provenance(true);
	prov.configWhat = "tab\there, line\nbreak, \x01 bell \"quoted\" back\\slash, caf\xc3\xa9";
	const auto doc = nlohmann::json::parse(summaryJson(ups, ev, TSystemOptions(), prov));
	EXPECT_EQ(doc["provenance"]["config"], prov.configWhat);
	EXPECT_DOUBLE_EQ(doc["coverage_in_map"].get<double>(), 0.55);  // written "0.550000"
	EXPECT_TRUE(doc["blind"]["episodes"].is_array());

	// What the drawing commands read back from a localise folder.
	const std::string dir = test::tempDir("eval_identity_provenance");
	writeSyntheticOutputs(dir, true);
	EXPECT_EQ(localiseProvenance(dir, "live"), "live/run b.rawlog");
	EXPECT_EQ(localiseProvenance(dir, "gt_fnv1a64"), "00000000000000cc");
	EXPECT_EQ(localiseProvenance(dir, "localisers"), "mono,invariant");
	EXPECT_EQ(localiseProvenance(dir, "no_such_key"), "");
	writeFileMakingDirs(dir + "/summary.json", "{\"provenance\": {\"live\": ");	// cut short
	EXPECT_EQ(localiseProvenance(dir, "live"), "");
	EXPECT_EQ(localiseProvenance(dir + "/missing", "live"), "");
}
