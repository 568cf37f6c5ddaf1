/* ShadyLoc tests: the leave-one-out evaluation (`shadyloc eval`,
 * docs/evaluation.md): the run list, the job plan, bad input, and results
 * that do not depend on how the jobs ran (one worker, two workers, one
 * process per job then --merge). */
#include "../support/TestSupport.h"

#include <shadyloc/eval/Evaluation.h>
#include <shadyloc/eval/LeaveOneOut.h>
#include <shadyloc/eval/RunList.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace fs = std::filesystem;
using namespace shadyloc;

namespace
{
/** Every regular file below dir (relative path -> bytes), timings left out:
 * they are the only outputs allowed to differ between runs. */
std::map<std::string, std::string> resultFiles(const std::string& dir)
{
	std::map<std::string, std::string> out;
	for (const auto& e : fs::recursive_directory_iterator(dir))
	{
		if (!e.is_regular_file()) continue;
		const std::string name = e.path().filename().string();
		if (name == "timing.json" || name == "job_timing.json") continue;
		out[fs::relative(e.path(), dir).string()] = test::fileContents(e.path().string());
	}
	return out;
}

std::string app() { return test::appPath() + " eval"; }
}  // namespace

// ---------------------------------------------------------------- run list
TEST(EvalRunList, ParsesCommentsBlankLinesAndRelativePaths)
{
	const std::string dir = test::tempDir("eval_runlist");
	fs::create_directories(dir + "/data");
	test::writeFileContents(dir + "/data/a.rawlog", "x");
	test::writeFileContents(dir + "/data/b.rawlog", "x");
	test::writeFileContents(dir + "/data/b.tum", "");
	test::writeFileContents(dir + "/data/c.rawlog", "x");	 // a rawlog of its own: the same one twice is refused
	test::writeFileContents(
		dir + "/runs.txt",
		"# name rawlog gt\n\n  a\tdata/a.rawlog   # no ground truth\nb data/b.rawlog data/b.tum\r\n" + std::string("c ") +
			dir + "/data/c.rawlog\n");
	const auto runs = eval::readRunList(dir + "/runs.txt");
	ASSERT_EQ(runs.size(), 3u);
	EXPECT_EQ(runs[0].name, "a");
	EXPECT_EQ(runs[0].line, 3);
	EXPECT_FALSE(runs[0].hasGt());
	EXPECT_EQ(runs[0].rawlog, "data/a.rawlog");	 // as written
	EXPECT_EQ(fs::path(runs[0].rawlogPath), fs::path(dir) / "data/a.rawlog");  // resolved against the list's folder
	EXPECT_EQ(runs[1].gt, "data/b.tum");
	EXPECT_EQ(fs::path(runs[1].gtPath), fs::path(dir) / "data/b.tum");
	EXPECT_EQ(runs[2].rawlogPath, dir + "/data/c.rawlog");	// absolute stays
	EXPECT_EQ(runs[2].line, 5);
}

TEST(EvalRunList, ErrorsNameFileLineAndRun)
{
	const std::string dir = test::tempDir("eval_runlist_bad");
	test::writeFileContents(dir + "/a.rawlog", "x");
	const auto error = [&](const std::string& text) {
		test::writeFileContents(dir + "/runs.txt", text);
		try
		{
			eval::readRunList(dir + "/runs.txt");
		}
		catch (const std::exception& e)
		{
			return std::string(e.what());
		}
		return std::string("(no error)");
	};
	const std::string where = dir + "/runs.txt:";
	EXPECT_EQ(error("a a.rawlog\na a.rawlog\n"), where + "2: run name 'a' is already used on line 1 (names must be unique)");
	EXPECT_NE(error("a a.rawlog\n# x\nb missing.rawlog\n").find(where + "3: run 'b': rawlog '"), std::string::npos);
	EXPECT_NE(error("a a.rawlog\nb a.rawlog nogt.tum\n").find(where + "2: run 'b': ground truth '"), std::string::npos);
	EXPECT_NE(error("a/b a.rawlog\nc a.rawlog\n").find(where + "1: run name 'a/b'"), std::string::npos);
	EXPECT_NE(error("a a.rawlog x.tum extra\n").find(where + "1: 4 fields"), std::string::npos);
	EXPECT_NE(error("a\n").find(where + "1: 1 field;"), std::string::npos);
	EXPECT_NE(error("a a.rawlog\n").find("1 run(s); leave-one-out needs at least 2"), std::string::npos);
	EXPECT_NE(error("").find("0 run(s)"), std::string::npos);
}

// ---------------------------------------------------------------- plan
TEST(EvalPlan, MapsFirstThenPairsInTheDocumentedOrder)
{
	std::vector<eval::TRun> runs(4);
	for (size_t i = 0; i < runs.size(); i++) runs[i].name = std::string(1, char('a' + i));
	const auto jobs = eval::makePlan(runs);
	ASSERT_EQ(jobs.size(), 4u + 2 * 4 * 3);	 // N maps + 2 N (N-1) pairs
	for (size_t k = 0; k < jobs.size(); k++) EXPECT_EQ(jobs[k].index, k);
	for (size_t i = 0; i < 4; i++)
	{
		EXPECT_TRUE(jobs[i].isMap);
		EXPECT_EQ(jobs[i].name, "map_" + runs[i].name);
	}
	EXPECT_EQ(jobs[4].name, "pair_a__b__baseline");
	EXPECT_EQ(jobs[5].name, "pair_a__b__combined");
	EXPECT_EQ(jobs[6].name, "pair_a__c__baseline");
	EXPECT_EQ(jobs[10].name, "pair_b__a__baseline");
	EXPECT_EQ(jobs.back().name, "pair_d__c__combined");
	for (const auto& j : jobs)
	{
		if (j.isMap) continue;
		EXPECT_NE(j.run, j.map);
		EXPECT_EQ(eval::pairJobIndex(4, j.run, j.map, j.system), j.index) << j.name;
		EXPECT_LT(j.map, 4u);  // its map job comes before every pair
	}
	EXPECT_EQ(eval::localisersOf(eval::EvalSystem::Baseline), std::vector<std::string>{"mono"});
	EXPECT_EQ(eval::localisersOf(eval::EvalSystem::Combined), (std::vector<std::string>{"mono", "invariant"}));
}

TEST(EvalPlan, ControlMapsAfterTheMapsAndControlPairsThird)
{
	std::vector<eval::TRun> runs(3);
	for (size_t i = 0; i < runs.size(); i++) runs[i].name = std::string(1, char('a' + i));
	const auto jobs = eval::makePlan(runs, true);
	ASSERT_EQ(jobs.size(), 2 * 3u + 3 * 3 * 2);  // 2N maps + 3 N (N-1) pairs
	EXPECT_EQ(eval::mapJobCount(3, true), 6u);
	for (size_t i = 0; i < 3; i++)
	{
		EXPECT_EQ(jobs[i].name, "map_" + runs[i].name);
		EXPECT_EQ(jobs[i].system, eval::EvalSystem::Baseline);
		EXPECT_EQ(jobs[3 + i].name, "control_map_" + runs[i].name);
		EXPECT_TRUE(jobs[3 + i].isMap);
		EXPECT_EQ(jobs[3 + i].system, eval::EvalSystem::Control);
	}
	EXPECT_EQ(jobs[6].name, "pair_a__b__baseline");
	EXPECT_EQ(jobs[7].name, "pair_a__b__combined");
	EXPECT_EQ(jobs[8].name, "pair_a__b__control");
	EXPECT_EQ(jobs.back().name, "pair_c__b__control");
	for (const auto& j : jobs)
	{
		EXPECT_EQ(jobs[j.index].index, j.index);
		if (j.isMap) continue;
		EXPECT_EQ(eval::pairJobIndex(3, j.run, j.map, j.system, true), j.index) << j.name;
		// The control localises on its own map, the others share one.
		const auto& m = jobs[j.mapJob];
		EXPECT_TRUE(m.isMap) << j.name;
		EXPECT_EQ(m.run, j.map) << j.name;
		EXPECT_EQ(m.system == eval::EvalSystem::Control, j.system == eval::EvalSystem::Control) << j.name;
	}
	EXPECT_EQ(eval::localisersOf(eval::EvalSystem::Control), std::vector<std::string>{"mono"});
	// Without the control the plan is the two-system one, job for job.
	const auto two = eval::makePlan(runs, false), plain = eval::makePlan(runs);
	ASSERT_EQ(two.size(), plain.size());
	for (size_t k = 0; k < two.size(); k++) EXPECT_EQ(two[k].name, plain[k].name);
}

TEST(EvalPlan, PooledBlindProbabilityIsTheRunsOwn)
{
	// The merge pools episodes through the same function evaluate() uses.
	eval::TEvalOptions o;
	const auto p = eval::blindProbability({10, 120, 30, 100, 5}, o);
	EXPECT_EQ(p.episodes, 5u);
	EXPECT_EQ(p.reaching, 2u);	// 120 and exactly 100
	EXPECT_DOUBLE_EQ(p.p, 0.4);
	EXPECT_LE(p.lo, p.p);
	EXPECT_GE(p.hi, p.p);
	EXPECT_GT(p.hi, p.lo);	// five episodes: a wide interval
	EXPECT_EQ(eval::blindProbability({}, o).episodes, 0u);
	EXPECT_EQ(eval::blindProbability({}, o).p, 0.0);
}

// ---------------------------------------------------------------- exact interval
// Reference values: Clopper-Pearson bounds as beta quantiles
// (lo = B^-1(0.025; k, n-k+1), hi = B^-1(0.975; k+1, n-k)) computed at 50
// digits with mpmath's regularised incomplete beta, an independent route from
// the binomial tail sums the code bisects; k = 0, n = 10 and k = 5, n = 10 are
// also the textbook values (0.3085; 0.1871 - 0.8129). Tolerance 1e-9: the
// bisection stops at 1e-15 in p, the log-space sums lose a few more digits.
TEST(LocalisationEvaluation, ClopperPearsonMatchesReferenceValues)
{
	struct Case
	{
		size_t k, n;
		double lo, hi;
	};
	const Case cases[] = {
		{0, 10, 0.0, 0.308497107819},
		{5, 10, 0.187086028447, 0.812913971553},
		{10, 10, 0.691502892181, 1.0},
		{1, 1, 0.025, 1.0},
		{0, 1, 0.0, 0.975},
		{1, 20, 0.00126508949795, 0.248732762772},
		{7, 50, 0.0581917003404, 0.267396002497},
		{4, 400, 0.00273119597124, 0.0254048009073},
		{3, 895, 0.000691787920688, 0.00976431858186},
		{0, 895, 0.0, 0.00411317066732},
		{0, 1101, 0.0, 0.00334487428702},
		{500, 1000, 0.468549172972, 0.531450827028},
		{2, 5000, 4.84455271182e-5, 0.00144418279587},
	};
	for (const auto& c : cases)
	{
		const auto r = eval::clopperPearson(c.k, c.n);
		EXPECT_NEAR(r.lo, c.lo, 1e-9) << c.k << " of " << c.n;
		EXPECT_NEAR(r.hi, c.hi, 1e-9) << c.k << " of " << c.n;
	}
	// No trial: no information.
	EXPECT_EQ(eval::clopperPearson(0, 0).lo, 0.0);
	EXPECT_EQ(eval::clopperPearson(0, 0).hi, 1.0);
	// Another confidence: k = 0 gives 1 - ((1 - c) / 2)^(1/n) in closed form.
	EXPECT_NEAR(eval::clopperPearson(0, 30, 0.90).hi, 1 - std::pow(0.05, 1.0 / 30), 1e-15);
	EXPECT_THROW(eval::clopperPearson(3, 2), std::invalid_argument);
	EXPECT_THROW(eval::clopperPearson(1, 2, 1.0), std::invalid_argument);
}

TEST(LocalisationEvaluation, ClopperPearsonBoundsSolveTheBinomialTails)
{
	// The defining equations, through the CDF itself, across sizes where the
	// pmf terms span hundreds of orders of magnitude.
	for (const size_t n : {1u, 7u, 60u, 895u, 20000u})
		for (const size_t k : {size_t(0), size_t(1), n / 3, n - 1, n})
		{
			if (k > n) continue;
			const auto r = eval::clopperPearson(k, n);
			ASSERT_LE(r.lo, r.hi);
			if (k < n) { EXPECT_NEAR(eval::binomialCdf(k, n, r.hi), 0.025, 1e-9) << k << " of " << n; }
			if (k > 0) { EXPECT_NEAR(1 - eval::binomialCdf(k - 1, n, r.lo), 0.025, 1e-9) << k << " of " << n; }
			const double p = static_cast<double>(k) / static_cast<double>(n);
			EXPECT_LE(r.lo, p);
			EXPECT_GE(r.hi, p);
		}
	// The CDF against exact sums (mpmath, 50 digits).
	EXPECT_NEAR(eval::binomialCdf(30, 100, 0.3), 0.54912360076879, 1e-12);
	EXPECT_NEAR(eval::binomialCdf(10, 2000, 0.01), 0.010522510740822, 1e-12);
	EXPECT_EQ(eval::binomialCdf(5, 5, 0.5), 1.0);
	EXPECT_EQ(eval::binomialCdf(0, 5, 0.0), 1.0);
	EXPECT_EQ(eval::binomialCdf(4, 5, 1.0), 0.0);
	EXPECT_THROW(eval::binomialCdf(1, 5, 1.5), std::invalid_argument);
}

TEST(LocalisationEvaluation, NoLongEpisodeStillHasAnUpperBound)
{
	// 40 short episodes: the bootstrap interval is [0, 0]; the exact one
	// keeps the doubt a finite count leaves, 1 - 0.025^(1/40) = 8.8 %.
	const std::vector<double> lengths(40, 12.0);
	const auto p = eval::blindProbability(lengths);
	EXPECT_EQ(p.reaching, 0u);
	EXPECT_EQ(p.p, 0.0);
	EXPECT_EQ(p.hi, 0.0);
	EXPECT_EQ(p.exact_lo, 0.0);
	EXPECT_NEAR(p.exact_hi, 1 - std::pow(0.025, 1.0 / 40), 1e-12);
	EXPECT_NEAR(p.exact_hi, 0.0880, 1e-4);
	// With episodes reaching the distance the exact interval is the pooled
	// count's, here 2 of 5 (mpmath: 0.0527449505 - 0.8533672004).
	const auto q = eval::blindProbability({10, 120, 30, 100, 5});
	EXPECT_NEAR(q.exact_lo, 0.0527449505, 1e-8);
	EXPECT_NEAR(q.exact_hi, 0.8533672004, 1e-8);
	// No episode at all: nothing known.
	const auto e = eval::blindProbability({});
	EXPECT_EQ(e.exact_lo, 0.0);
	EXPECT_EQ(e.exact_hi, 1.0);
}

// ---------------------------------------------------------------- the command
TEST(EvalApp, BadInputNamesTheCulpritAndLeavesNothing)
{
	const std::string dir = test::tempDir("eval_bad");
	test::writeSyntheticRawlog(dir + "/a.rawlog", 2, false);
	test::writeSyntheticRawlog(dir + "/b.rawlog", 2, false);
	test::writeSyntheticRawlog(dir + "/wide.rawlog", 2, false, 200, 120);  // another camera
	std::string out;
	const auto run = [&](const std::string& args) { return test::runCommand(app() + " " + args, &out); };

	// A run list naming a file that is not there.
	test::writeFileContents(dir + "/missing.txt", "a a.rawlog\n\nb gone.rawlog\n");
	EXPECT_EQ(run("--runs " + dir + "/missing.txt -o " + dir + "/o1"), 1);
	EXPECT_NE(out.find("missing.txt:3: run 'b': rawlog '"), std::string::npos) << out;
	EXPECT_NE(out.find("gone.rawlog' does not exist"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/o1"));

	// Duplicate names.
	test::writeFileContents(dir + "/dup.txt", "a a.rawlog\na b.rawlog\n");
	EXPECT_EQ(run("--runs " + dir + "/dup.txt -o " + dir + "/o2"), 1);
	EXPECT_NE(out.find("dup.txt:2: run name 'a' is already used on line 1"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/o2"));

	// Runs of different cameras: both named, with their lines.
	test::writeFileContents(dir + "/cams.txt", "a a.rawlog\nb b.rawlog\nw wide.rawlog\n");
	EXPECT_EQ(run("--runs " + dir + "/cams.txt -o " + dir + "/o3 --plan"), 1);
	EXPECT_NE(out.find("cams.txt:3: run 'w': its camera"), std::string::npos) << out;
	EXPECT_NE(out.find("200x120 px"), std::string::npos) << out;
	EXPECT_NE(out.find("differs from run 'a''s (line 1"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/o3"));

	// An unknown key in one of several configs: that file and line.
	test::writeFileContents(dir + "/ok.ini", "[localise]\nthreads = 1\n");
	test::writeFileContents(dir + "/typo.ini", "[localiser]\nmin_inliers = 12\nmin_inlier = 3\n");
	test::writeFileContents(dir + "/runs.txt", "a a.rawlog\nb b.rawlog\n");
	EXPECT_EQ(run("--runs " + dir + "/runs.txt -o " + dir + "/o4 -c " + dir + "/ok.ini -c " + dir + "/typo.ini"), 1);
	EXPECT_NE(out.find(dir + "/typo.ini:3: [localiser] min_inlier: unknown key"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/o4"));

	// --job and --merge need the plan; --job K within it.
	const std::string o5 = dir + "/o5", base = "--runs " + dir + "/runs.txt -o " + o5 + " -c " + dir + "/ok.ini";
	EXPECT_EQ(run(base + " --job 0"), 1);
	EXPECT_NE(out.find("plan.tsv' does not exist: make the plan first"), std::string::npos) << out;
	ASSERT_EQ(run(base + " --plan"), 0) << out;
	EXPECT_EQ(out, "maps 0 1\npairs 2 5\n");
	EXPECT_EQ(run(base + " --job 6"), 1);
	EXPECT_NE(out.find("--job 6: the plan in '" + o5 + "' has jobs 0..5"), std::string::npos) << out;
	// A plan made with other configs is refused.
	EXPECT_EQ(run("--runs " + dir + "/runs.txt -o " + o5 + " --job 2"), 1);
	EXPECT_NE(out.find("made with other configs"), std::string::npos) << out;

	// A pair whose map job has not run: the map job to run is named.
	EXPECT_EQ(run(base + " --job 2"), 1);
	EXPECT_NE(out.find("job 2 (live run 'a' against the map of 'b', baseline): the map of run 'b' is missing"), std::string::npos)
		<< out;
	EXPECT_NE(out.find("run map job 1 first"), std::string::npos) << out;
	// A map that fails to load (a damaged job output): named, with its job.
	fs::create_directories(o5 + "/jobs/map_b");
	test::writeFileContents(o5 + "/jobs/map_b/map.kfmap", "not a map");
	EXPECT_EQ(run(base + " --job 2"), 1);
	EXPECT_NE(out.find("the map of run 'b' ('" + o5 + "/jobs/map_b/map.kfmap', from map job 1) fails to load"), std::string::npos)
		<< out;
	EXPECT_NE(out.find("run map job 1 again"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(o5 + "/jobs/pair_a__b__baseline"));
	// Merging with jobs missing names every one of them, writes nothing.
	EXPECT_EQ(run(base + " --merge"), 1);
	EXPECT_NE(out.find("cannot merge: 6 of 6 jobs"), std::string::npos) << out;
	EXPECT_NE(out.find("job 1 (map of run 'b')"), std::string::npos) << out;
	EXPECT_NE(out.find("job 5 (live run 'b' against the map of 'a', combined): no output"), std::string::npos) << out;
	for (const char* f : {"table1.md", "table1.csv", "eval.json", "timing.json", "summary.md", "figures_inputs.tsv", "pairs"})
		EXPECT_FALSE(fs::exists(o5 + "/" + f)) << f;
	// One mode at a time.
	EXPECT_EQ(run(base + " --plan --merge"), 2);
}

namespace
{
/** A pair job's record as runPairJob writes it (pair.tsv), with `edit`
 * applied: one line replaced by key. */
std::string pairRecord(const std::string& live, const std::string& map, const std::string& system,
	const std::map<std::string, std::string>& edit = {})
{
	std::vector<std::pair<std::string, std::string>> lines = {
		{"live", live}, {"map", map}, {"system", system},
		{"localisers", system == "baseline" ? "mono" : "mono,invariant"}, {"frames", "10"}, {"ground_truth", "0"},
		{"in_map_frames", "8"}, {"fixes", "6"}, {"fixes_in_map", "5"}, {"true_fixes", "0"},
		{"true_fixes_in_map", "0"}, {"false_fixes", "0"}, {"unverifiable", "0"}, {"total_m", "9"},
		{"blind_m", "2.5"}, {"before_first_fix_m", "1"}, {"first_fix_frame", "2"}, {"global_searches", "1"},
		{"channel", "mono\t6\t6\t5\t0\t0\t0\t0"}, {"bins", "0\t0\t0"}, {"episode", "before_first_fix\t1"},
		{"episode", "at_end\t1.5"}};
	std::string t = "# shadyloc eval pair v1\n";
	for (auto& [k, v] : lines) t += k + "\t" + (edit.count(k) ? edit.at(k) : v) + "\n";
	return t + "end\n";
}
}  // namespace

// The merge trusted each job's record: a coverage above 100 % or a negative
// count went into Table I. Each record is checked (schema, ranges, counts
// consistent) and the job at fault is named.
TEST(EvalApp, MergeRefusesJobRecordsOutOfRange)
{
	const std::string dir = test::tempDir("eval_merge_check");
	test::writeSyntheticRawlog(dir + "/a.rawlog", 2, false);
	test::writeSyntheticRawlog(dir + "/b.rawlog", 2, false);
	test::writeFileContents(dir + "/runs.txt", "a a.rawlog\nb b.rawlog\n");
	const std::string o = dir + "/o", base = app() + " --runs " + dir + "/runs.txt -o " + o;
	std::string out;
	ASSERT_EQ(test::runCommand(base + " --plan", &out), 0) << out;
	for (const char* r : {"a", "b"})
	{
		const std::string d = o + "/jobs/map_" + std::string(r);
		fs::create_directories(d);
		test::writeFileContents(d + "/map.kfmap", "");
		test::writeFileContents(d + "/map.tsv", "# shadyloc eval map v1\nrun\t" + std::string(r) +
									  "\nframes\t10\nkeyframes\t4\ngt_keyframes\t0\nbreaks\t0\npath_m\t9\n");
	}
	const auto writePairs = [&](const std::string& badJob, const std::map<std::string, std::string>& edit) {
		for (const auto& [live, map] : {std::pair<std::string, std::string>{"a", "b"}, {"b", "a"}})
			for (const char* sys : {"baseline", "combined"})
			{
				const std::string name = "pair_" + live + "__" + map + "__" + sys, d = o + "/jobs/" + name;
				fs::create_directories(d);
				for (const char* f : {"frames.csv", "summary.json", "trajectory.tum"}) test::writeFileContents(d + "/" + f, "");
				test::writeFileContents(d + "/pair.tsv", pairRecord(live, map, sys, name == badJob ? edit : std::map<std::string, std::string>{}));
			}
	};
	struct TCase
	{
		std::map<std::string, std::string> edit;
		std::string expect;
	};
	for (const auto& c : std::vector<TCase>{
			 {{{"fixes_in_map", "12"}}, "coverage above 100 %"},
			 {{{"fixes", "-3"}}, "'-3' is not a count"},
			 {{{"total_m", "nan"}}, "total_m and blind_m must be lengths >= 0"},
			 {{{"channel", "mono\t6\t7\t5\t0\t0\t0\t0"}}, "used 7 > accepted 6"},
			 {{{"bins", "3\t2\t1"}}, "accuracy bins"},
			 {{{"blind_m", "7"}}, "sum of the episodes"}})
	{
		writePairs("pair_b__a__combined", c.edit);
		EXPECT_EQ(test::runCommand(base + " --merge", &out), 1) << out;
		EXPECT_NE(out.find("job 5 (live run 'b' against the map of 'a', combined)"), std::string::npos) << out;
		EXPECT_NE(out.find("pair_b__a__combined/pair.tsv"), std::string::npos) << out;
		EXPECT_NE(out.find(c.expect), std::string::npos) << c.expect << ": " << out;
		EXPECT_EQ(out.find("job 4 ("), std::string::npos) << out;  // the others are fine
		EXPECT_FALSE(fs::exists(o + "/table1.md"));
	}
}

TEST(EvalApp, ResultsIdenticalAcrossWorkersAndJobs)
{
	// Three traversals of the simulator, 12 frames each (about 8 m: the
	// global search finds its place within a few frames, so the pairs have
	// fixes), evaluated three ways: two workers, one worker, and one process
	// per job then --merge, from another working directory and output folder.
	const std::string dir = test::tempDir("eval_identical");
	const std::string src = SHADYLOC_SOURCE_DIR;
	std::string out;
	ASSERT_EQ(
		test::runCommand(
			test::appPath() + " sim -q -c " + src + "/config/sim.ini -o " + dir +
				"/data --frames 12 --traversals noon,overcast,morning_low_sun",
			&out),
		0)
		<< out;
	test::writeFileContents(
		dir + "/data/runs.txt",
		"# three lighting conditions\nnoon noon.rawlog noon.tum\novercast overcast.rawlog overcast.tum\n"
		"morning morning_low_sun.rawlog morning_low_sun.tum\n");
	const std::string cfg = " -c " + src + "/config/vo_sim.ini -c " + src + "/config/localise_sim.ini";
	const std::string runs = " --runs " + dir + "/data/runs.txt";

	ASSERT_EQ(test::runCommand(app() + runs + " -o " + dir + "/j2" + cfg + " -j 2", &out), 0) << out;
	EXPECT_NE(out.find("| **mean** | 2 |"), std::string::npos) << out;
	ASSERT_EQ(test::runCommand(app() + " -q" + runs + " -o " + dir + "/j1" + cfg + " -j 1", &out), 0) << out;

	// The cluster way: the plan's ranges, every job alone, the merge.
	const std::string jobs = dir + "/cluster/out";
	fs::create_directories(jobs);
	const std::string rel = "cd " + dir + "/cluster && " + app() + " -q --runs ../data/runs.txt -o out" + cfg;
	ASSERT_EQ(test::runCommand(rel + " --plan", &out), 0) << out;
	EXPECT_EQ(out, "maps 0 2\npairs 3 14\n");
	for (int k = 14; k >= 3; k--)  // pairs first: they must wait for their maps
		EXPECT_EQ(test::runCommand(rel + " --job " + std::to_string(k), &out), 1) << "job " << k;
	for (int k = 0; k <= 14; k++) ASSERT_EQ(test::runCommand(rel + " --job " + std::to_string(k), &out), 0) << out;
	// A job run again replaces its output.
	ASSERT_EQ(test::runCommand(rel + " --job 4", &out), 0) << out;
	ASSERT_EQ(test::runCommand(rel + " --merge", &out), 0) << out;

	const auto a = resultFiles(dir + "/j2"), b = resultFiles(dir + "/j1"), c = resultFiles(jobs);
	for (const char* f :
		 {"table1.md", "table1.csv", "summary.md", "eval.json", "figures_inputs.tsv", "plan.tsv",
		  "pairs/noon__overcast__combined/frames.csv", "pairs/morning__noon__baseline/summary.json",
		  "pairs/overcast__morning__combined/trajectory.tum", "jobs/map_noon/map.kfmap",
		  "figures/figure7_noon__overcast.png", "figures/figure8_morning.png", "figures/figure9.png"})
		EXPECT_TRUE(a.count(f)) << f;
	// Outputs and plan, the map jobs (map, record), pairs/ (3 files each),
	// the pair jobs (those 3, the solve log and the record), figures (Figure 7 per ordered
	// pair, Figure 8 per live run, one Figure 9), and the marker of each
	// folder replaced as a whole (15 jobs, pairs/, figures/); the PNGs
	// compare too.
	EXPECT_EQ(a.size(), 6u + 3 * 2 + 12 * 3 + 12 * 5 + 6 + 3 + 1 + 15 + 2);
	const auto same = [](const auto& x, const auto& y, const char* what) {
		EXPECT_EQ(x.size(), y.size()) << what;
		for (const auto& [name, bytes] : x)
		{
			const auto it = y.find(name);
			ASSERT_NE(it, y.end()) << what << ": " << name << " missing";
			EXPECT_TRUE(bytes == it->second) << what << ": " << name << " differs";
		}
	};
	same(a, b, "-j 2 vs -j 1");
	same(a, c, "-j 2 vs --plan/--job/--merge");
	EXPECT_TRUE(fs::exists(dir + "/j2/timing.json"));

	// Table I: a row per live run and the mean; true coverage never above
	// self-reported (a true fix is a fix), and the runs did localise.
	std::istringstream csv(a.at("table1.csv"));
	std::string line;
	std::getline(csv, line);
	EXPECT_EQ(line, "live,maps,baseline_pct,invariant_pct,combined_pct,baseline_self_pct,invariant_self_pct,combined_self_pct");
	std::vector<std::string> names;
	while (std::getline(csv, line))
	{
		std::vector<double> v;
		std::stringstream s(line);
		std::string f;
		std::getline(s, f, ',');
		names.push_back(f);
		std::getline(s, f, ',');
		EXPECT_EQ(f, "2");
		while (std::getline(s, f, ',')) v.push_back(std::stod(f));
		ASSERT_EQ(v.size(), 6u) << line;
		for (int k = 0; k < 3; k++) EXPECT_LE(v[k], v[k + 3] + 1e-9) << line;
		EXPECT_GT(v[3], 0) << line;	 // the baseline localised
		EXPECT_GT(v[5], 0) << line;	 // the combined system too
	}
	EXPECT_EQ(names, (std::vector<std::string>{"noon", "overcast", "morning", "mean"}));
	const std::string js = a.at("eval.json");
	EXPECT_NE(js.find("\"format\": \"shadyloc eval\",\n  \"version\": 1"), std::string::npos);
	EXPECT_NE(js.find("\"runs_file\": \"runs.txt\""), std::string::npos);
	EXPECT_NE(js.find("\"config\": \"vo_sim.ini + localise_sim.ini\""), std::string::npos);
	EXPECT_NE(js.find("\"rawlog\": \"noon.rawlog\", \"rawlog_fnv1a64\": \""), std::string::npos);
	EXPECT_EQ(js.find(dir), std::string::npos) << "no absolute paths in the results";
	EXPECT_NE(a.at("figures_inputs.tsv").find("noon\tovercast\tpairs/noon__overcast__baseline/frames.csv\tpairs/noon__overcast__combined/frames.csv\n"),
			  std::string::npos);
}

// ---------------------------------------------------------------- the control (--control)
namespace
{
/** The mean and largest landmark count per keyframe of a map's mono channel, and its stored budget. */
struct TMapBudget
{
	double mean = 0;
	size_t most = 0;
	int budget = 0;
};
TMapBudget monoLandmarks(const std::string& path)
{
	const auto map = CKeyframeMap::LoadFromFile(path);
	TMapBudget b;
	b.budget = map->options.landmarks_per_keyframe;
	for (uint32_t k = 0; k < map->keyframeCount(); k++)
	{
		const size_t n = map->measurements(k, "mono").size();
		b.mean += static_cast<double>(n) / static_cast<double>(map->keyframeCount());
		b.most = std::max(b.most, n);
	}
	return b;
}
}  // namespace

TEST(EvalControl, BadLayerIsRefusedNamingItBeforeAnyJob)
{
	const std::string dir = test::tempDir("eval_control_bad");
	test::writeSyntheticRawlog(dir + "/a.rawlog", 2, false);
	test::writeSyntheticRawlog(dir + "/b.rawlog", 2, false);
	test::writeFileContents(dir + "/runs.txt", "a a.rawlog\nb b.rawlog\n");
	test::writeFileContents(dir + "/ok.ini", "[localise]\nthreads = 1\n");
	std::string out;
	const std::string base = app() + " --runs " + dir + "/runs.txt -c " + dir + "/ok.ini";
	const auto refused = [&](const std::string& control, const std::string& o, const std::string& expect) {
		EXPECT_EQ(test::runCommand(base + " -o " + dir + "/" + o + " --control " + control, &out), 1) << out;
		EXPECT_NE(out.find(expect), std::string::npos) << expect << ": " << out;
		EXPECT_FALSE(fs::exists(dir + "/" + o)) << o;  // nothing written, no job run
	};
	refused(dir + "/gone.ini", "o1", "--control '" + dir + "/gone.ini': the control's config does not exist");

	// An unknown key: the control's file and line, though the -c files are fine.
	test::writeFileContents(dir + "/typo.ini", "[features]\nmax_per_cell = 60\nmax_per_cel_right = 240\n");
	refused(dir + "/typo.ini", "o2", dir + "/typo.ini:3: [features] max_per_cel_right: unknown key");
	// An unknown section.
	test::writeFileContents(dir + "/sect.ini", "[feature]\nmax_per_cell = 60\n");
	refused(dir + "/sect.ini", "o3", dir + "/sect.ini:1: ");
	EXPECT_NE(out.find("[feature]"), std::string::npos) << out;
	// A value out of range.
	test::writeFileContents(dir + "/range.ini", "[map]\nlandmarks_per_keyframe = -4\n");
	refused(dir + "/range.ini", "o4", dir + "/range.ini:");
	EXPECT_NE(out.find("landmarks_per_keyframe: must be >= 0"), std::string::npos) << out;
	// A layer that sets nothing would make the control the baseline.
	test::writeFileContents(dir + "/empty.ini", "; nothing\n[features]\n");
	refused(dir + "/empty.ini", "o5", "--control '" + dir + "/empty.ini': sets no key");
	// The same file twice in one layer is refused by the layering.
	test::writeFileContents(dir + "/twice.ini", "[features]\nmax_per_cell = 60\nmax_per_cell = 70\n");
	refused(dir + "/twice.ini", "o6", dir + "/twice.ini");

	// A plan made with a control wants it again at --job and --merge; one made without refuses it.
	test::writeFileContents(dir + "/budget.ini", "[features]\nmax_per_cell = 60\n");
	const std::string o7 = " -o " + dir + "/o7";
	ASSERT_EQ(test::runCommand(base + o7 + " --control " + dir + "/budget.ini --plan", &out), 0) << out;
	EXPECT_EQ(out, "maps 0 3\npairs 4 9\n");
	const std::string plan = test::fileContents(dir + "/o7/plan.tsv");
	EXPECT_NE(plan.find("\n# control_fnv1a64\t"), std::string::npos) << plan;
	EXPECT_NE(plan.find("\n2\tmap\ta\t-\tcontrol\tcontrol_map_a\n"), std::string::npos) << plan;
	EXPECT_NE(plan.find("\n9\tpair\tb\ta\tcontrol\tpair_b__a__control\n"), std::string::npos) << plan;
	EXPECT_EQ(test::runCommand(base + o7 + " --job 0", &out), 1);
	EXPECT_NE(out.find("made with --control: give the same --control file"), std::string::npos) << out;
	test::writeFileContents(dir + "/budget2.ini", "[features]\nmax_per_cell = 61\n");
	EXPECT_EQ(test::runCommand(base + o7 + " --control " + dir + "/budget2.ini --merge", &out), 1);
	EXPECT_NE(out.find("made with another control than '" + dir + "/budget2.ini'"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(base + o7 + " --control " + dir + "/budget.ini --job 6", &out), 1);
	EXPECT_NE(out.find("job 6 (live run 'a' against the map of 'b', control): the map of run 'b' is missing"),
			  std::string::npos) << out;
	EXPECT_NE(out.find("run map job 3 first ("), std::string::npos) << out;
	EXPECT_NE(out.find("--control " + dir + "/budget.ini --job 3)"), std::string::npos) << out;
	const std::string o8 = " -o " + dir + "/o8";
	ASSERT_EQ(test::runCommand(base + o8 + " --plan", &out), 0) << out;
	EXPECT_EQ(out, "maps 0 1\npairs 2 5\n");
	EXPECT_EQ(test::runCommand(base + o8 + " --control " + dir + "/budget.ini --job 0", &out), 1);
	EXPECT_NE(out.find("made without --control"), std::string::npos) << out;
}

TEST(EvalControl, ThirdSystemOnMapsOfItsOwnBudget)
{
	// The smallest data of the eval tests (ResultsIdenticalAcrossWorkersAndJobs):
	// the simulator's traversals, 12 frames each, here two of them.
	const std::string dir = test::tempDir("eval_control");
	const std::string src = SHADYLOC_SOURCE_DIR;
	std::string out;
	ASSERT_EQ(
		test::runCommand(
			test::appPath() + " sim -q -c " + src + "/config/sim.ini -o " + dir + "/data --frames 12 --traversals noon,overcast",
			&out),
		0)
		<< out;
	test::writeFileContents(dir + "/data/runs.txt", "noon noon.rawlog noon.tum\novercast overcast.rawlog overcast.tum\n");
	const std::string base = app() + " -q --runs " + dir + "/data/runs.txt -c " + src + "/config/vo_sim.ini -c " + src +
							 "/config/localise_sim.ini";
	const std::string control = " --control " + src + "/config/control_budget.ini";
	ASSERT_EQ(test::runCommand(base + " -j 1 -o " + dir + "/out" + control, &out), 0) << out;
	const std::string o = dir + "/out";

	// The control's maps were surveyed with the layer: its budget stored, and
	// more monochrome landmarks kept per keyframe than the baseline's maps.
	for (const char* run : {"noon", "overcast"})
	{
		const auto base = monoLandmarks(o + "/jobs/map_" + std::string(run) + "/map.kfmap");
		const auto ctl = monoLandmarks(o + "/jobs/control_map_" + std::string(run) + "/map.kfmap");
		EXPECT_EQ(base.budget, 300) << run;
		EXPECT_EQ(ctl.budget, 600) << run;
		EXPECT_LE(base.most, 300u) << run;
		EXPECT_GT(ctl.most, 300u) << run;
		EXPECT_GT(ctl.mean, 1.2 * base.mean) << run << ": " << ctl.mean << " against " << base.mean;
	}

	// Table I: the control's columns after the others, plausible numbers.
	const std::string csv = test::fileContents(o + "/table1.csv");
	EXPECT_EQ(csv.substr(0, csv.find('\n')),
			  "live,maps,baseline_pct,invariant_pct,combined_pct,baseline_self_pct,invariant_self_pct,"
			  "combined_self_pct,control_pct,control_self_pct");
	const std::string md = test::fileContents(o + "/table1.md");
	EXPECT_NE(md.find("| live run | maps | baseline | invariant alone | combined | control | self-reported"),
			  std::string::npos) << md;
	EXPECT_NE(md.find("with control_budget.ini layered over the configs"), std::string::npos) << md;
	const auto js = nlohmann::json::parse(test::fileContents(o + "/eval.json"));
	const auto& mean = js["table1"]["mean"];
	for (const char* k : {"baseline", "combined", "control"})
	{
		ASSERT_TRUE(mean[k].is_number()) << k << ": " << mean.dump();
		EXPECT_GT(mean[k].get<double>(), 0.3) << k;	 // every system localised
		EXPECT_LE(mean[k].get<double>(), mean[std::string(k) + "_self"].get<double>() + 1e-9) << k;
	}
	// The same metrics as the baseline's: fixes against ground truth with the
	// exact upper bound of the false share, blind episodes.
	const auto& gt = js["ground_truth"]["control"];
	EXPECT_EQ(gt["pairs"], 2);
	EXPECT_GT(gt["fixes_used"]["true"].get<int>(), 0);
	EXPECT_TRUE(gt["fixes_used"]["false_share_hi95"].is_number());
	ASSERT_EQ(gt["channels"].size(), 1u);
	EXPECT_EQ(gt["channels"][0]["channel"], "mono");
	EXPECT_EQ(js["blind"]["control"]["pairs"], 2);
	EXPECT_EQ(js["plan"]["maps"], 4);
	EXPECT_EQ(js["plan"]["pairs"], 6);
	EXPECT_EQ(js["provenance"]["control_config"], "control_budget.ini");
	EXPECT_EQ(js["provenance"]["config"], "vo_sim.ini + localise_sim.ini");
	EXPECT_EQ(js["runs"][0]["control_map"]["file"], "jobs/control_map_noon/map.kfmap");
	const std::string sm = test::fileContents(o + "/summary.md");
	EXPECT_NE(sm.find("| control | (used) |"), std::string::npos) << sm;
	EXPECT_NE(sm.find("- control: P(100 m) = "), std::string::npos) << sm;
	// Each control pair is the mono localiser with the layered config.
	const auto pair = nlohmann::json::parse(test::fileContents(o + "/pairs/noon__overcast__control/summary.json"));
	EXPECT_EQ(pair["provenance"]["config"], "vo_sim.ini + localise_sim.ini + control_budget.ini");
	EXPECT_EQ(pair["provenance"]["localisers"], "mono");
	EXPECT_EQ(pair["provenance"]["map"], "jobs/control_map_overcast/map.kfmap");

	// The merge alone gives the same tables; without the control it refuses the plan.
	const std::string table = test::fileContents(o + "/table1.md");
	ASSERT_EQ(test::runCommand(base + " -o " + o + control + " --merge", &out), 0) << out;
	EXPECT_EQ(test::fileContents(o + "/table1.md"), table);
	EXPECT_EQ(test::runCommand(base + " -o " + o + " --merge", &out), 1);
	EXPECT_NE(out.find("made with --control"), std::string::npos) << out;
}
