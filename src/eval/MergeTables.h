/* ShadyLoc — the leave-one-out merge in three steps (private to the eval
 * area; docs/evaluation.md): collect every job's record, make the tables
 * (Table I per live run, each system's numbers pooled over its pairs), then
 * one writer per output file. Each writer is a function of the tables
 * alone, so the same records give the same bytes however the jobs ran. */
#pragma once

#include <shadyloc/eval/Evaluation.h>
#include <shadyloc/eval/LeaveOneOut.h>

#include "EvalRecords.h"

#include <array>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace shadyloc::eval
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/** a / b, NaN when b is 0 (a share of nothing is unknown, not 0). */
double ratio(size_t a, size_t b);
/** The exact 95 % upper bound (Clopper-Pearson) of a false share: what the
 * localisation issue's "under 0.1 %" is judged by (NaN without fixes). */
double falseShareUpper(size_t falseFixes, size_t fixes);
/** Nearest-rank percentile (as localise's timing); NaN if empty. */
double percentile(std::vector<double> v, double p);

/** The files of a pair job that the merge requires and publishes in OUTDIR/pairs/. */
constexpr const char* kPairFiles[] = {"frames.csv", "summary.json", "trajectory.tum"};

/** A pair's folder under OUTDIR/pairs: "<live>__<map>__<system>". */
std::string pairDirName(const TEvalJob& j, const std::vector<TRun>& runs);

/** One Table I row: per live run, averaged over the maps. */
struct TRow
{
	std::string live;
	size_t maps = 0;
	bool truth = false;	 //!< every pair of the row has ground truth
	double base = kNaN, inv = kNaN, comb = kNaN;  //!< true coverage [0..1]
	double baseSelf = kNaN, invSelf = kNaN, combSelf = kNaN;  //!< self-reported [0..1]
	double ctl = kNaN, ctlSelf = kNaN;	//!< the control's, with --control [0..1]
};

/** A system's numbers pooled over its pairs. */
struct TPooled
{
	size_t pairs = 0, gtPairs = 0;
	std::map<std::string, TPairChannel> channels;  //!< over pairs with ground truth
	std::vector<std::string> channelOrder;
	size_t trueFixes = 0, falseFixes = 0, unverifiable = 0;	 //!< the fixes used, pairs with ground truth
	std::vector<double> errM, errDeg;
	size_t binFrames = 0;
	std::array<size_t, 3> bins = {0, 0, 0};
	std::vector<double> between;  //!< blind episodes between fixes [m], all pairs
	size_t atEnd = 0, beforeFirst = 0, neverLocalised = 0;
	double blindM = 0, totalM = 0;
	TBlindProbability blind;  //!< of `between`
};

/** What the merge's outputs are written from: its inputs, the jobs'
 * records, and the tables made of them. */
struct TMerged
{
	TMerged(const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs)
		: outDir(outDir), in(in), jobs(jobs)
	{
	}
	std::string outDir;
	const TEvalInputs& in;
	const std::vector<TEvalJob>& jobs;

	// ---- collected
	std::vector<TMapRecord> maps;  //!< by run
	std::vector<TMapRecord> controlMaps;  //!< the control's, by run (with --control)
	std::vector<TPairRecord> pairs;	 //!< by job index (empty for map jobs)

	// ---- tables
	TEvalOptions evo;  //!< the definitions the jobs evaluated with
	std::vector<TRow> rows;
	TRow mean;
	TPooled pooled[3];	//!< baseline, combined, control (by EvalSystem)

	const std::vector<TRun>& runs() const { return in.runs; }
	bool control() const { return in.hasControl(); }
	/** The systems evaluated: 2, or 3 with the control (a prefix of kSystemNames). */
	int systems() const { return control() ? 3 : 2; }
	/** Some pair of any system had ground truth. */
	bool anyGt() const { return pooled[0].gtPairs + pooled[1].gtPairs + pooled[2].gtPairs > 0; }
	/** The pair job of (live, map, system) in this plan. */
	const TEvalJob& pairJob(size_t live, size_t map, EvalSystem s) const
	{
		return jobs[pairJobIndex(runs().size(), live, map, s, control())];
	}
};

/** The systems' names in output order (index into TMerged::pooled, as EvalSystem). */
constexpr const char* kSystemNames[3] = {"baseline", "combined", "control"};

/** Collect: every job's record into m.maps and m.pairs. Missing or
 * unreadable outputs throw one error naming every such job and how to run
 * it again. */
void collectRecords(TMerged& m);
/** Tables: Table I's rows and mean, the systems pooled (m.rows, m.mean, m.pooled). */
void makeTables(TMerged& m);

// ---- one writer per output (MergeOutputs.cpp)
std::string table1Markdown(const TMerged& m);
std::string table1Csv(const TMerged& m);
std::string summaryMarkdown(const TMerged& m);
std::string evalJson(const TMerged& m);
/** timing.json: the whole run's wall time (< 0: unknown) and each job's, from its job_timing.json. */
std::string evalTimingJson(const TMerged& m, double wall_s);
/** figures_inputs.tsv: per (live, map), the two frames.csv Figures 7-9 are drawn from. */
std::string figuresInputs(const TMerged& m);

}  // namespace shadyloc::eval
