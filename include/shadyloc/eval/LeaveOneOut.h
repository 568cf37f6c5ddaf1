/* ShadyLoc — the paper's evaluation (McManus et al. 2014, Section IV):
 * exhaustive leave-one-out over N runs. Every run is surveyed once into a
 * map; every run is then localised against the map of every other run, once
 * with the baseline system alone (`mono`) and once with the combined system
 * (`mono,invariant`), as separate runs (docs/localisation.md says why).
 *
 * The work is a plan of independent jobs, in a fixed order:
 *   jobs 0 .. N-1        the map of run i (runs in list order);
 *   jobs N .. N+2N(N-1)-1  for each live run i (list order), each other run j
 *                        (list order), the baseline then the combined system:
 *                        job N + 2 (i (N-1) + j') + s, j' = j - (j > i),
 *                        s = 0 baseline, 1 combined.
 * With a budget-matched control (--control INI: the baseline with INI
 * layered over the configs, docs/evaluation.md) the control's own maps come
 * after the maps, and each (live, map) has three pair jobs:
 *   jobs 0 .. N-1        the map of run i;
 *   jobs N .. 2N-1       the control's map of run i (INI layered);
 *   jobs 2N ..           job 2N + 3 (i (N-1) + j') + s, s = 2 the control.
 * A job writes its outputs into OUTDIR/jobs/<job name>/ as a whole or not at
 * all; merge() combines them into Table I, the ground-truth summaries, the
 * pooled blind-distance distributions and one versioned eval.json. Results
 * do not depend on how the jobs ran (one process with a worker pool, or one
 * process per job on a cluster): byte for byte, timings apart
 * (docs/evaluation.md).
 */
#pragma once

#include <shadyloc/eval/RunList.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/system/COutputLogger.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace shadyloc::eval
{
/** plan.tsv's and the job records' format version. */
constexpr int kPlanVersion = 1;
/** eval.json's format version. */
constexpr int kEvalVersion = 1;

enum class EvalSystem
{
	Baseline,  //!< --localisers mono
	Combined,  //!< --localisers mono,invariant
	Control	 //!< --localisers mono, on maps and frames made with the control's layered config
};
const char* toString(EvalSystem s);	 //!< "baseline", "combined", "control"
/** The localisers of a system, in policy order. */
std::vector<std::string> localisersOf(EvalSystem s);
/** The systems of a plan, in job order: baseline, combined (, control). */
std::vector<EvalSystem> systemsOf(bool control);

struct TEvalJob
{
	size_t index = 0;
	bool isMap = false;
	size_t run = 0;	 //!< map job: the surveyed run; pair job: the live run (indices into the run list)
	size_t map = 0;	 //!< pair job: the run whose map it uses
	size_t mapJob = 0;	//!< pair job: the index of the map job that makes that map
	/** Pair job: the system. Map job: Baseline for the map the baseline and
	 * the combined system share, Control for the control's own. */
	EvalSystem system = EvalSystem::Baseline;
	/** "map_<run>", "control_map_<run>" or "pair_<live>__<map>__<system>": its folder in OUTDIR/jobs/ */
	std::string name;
};

/** The folder name of a map job: "map_<run>" (Baseline, Combined) or "control_map_<run>". */
std::string mapJobName(const std::string& run, EvalSystem s);

/** What an evaluation runs on: the run list, the config files (read
 * together, as `shadyloc localise -c ... -c ...` does), and the build. */
struct TEvalInputs
{
	std::string runsPath;
	std::vector<TRun> runs;
	std::vector<std::string> configPaths;
	std::string configText;	 //!< the files' text, concatenated
	std::string configWhat;	 //!< their names, " + "-joined ("(no config)")
	std::string buildCommit = "unknown";
	/** The budget-matched control's layer (--control; "" = no control): an
	 * .ini applied over configPaths for the control system's maps and pairs. */
	std::string controlPath;
	std::string controlLayerText;  //!< that file's text
	std::string controlText;  //!< configText with the layer after it: what the control runs with
	std::string controlWhat;  //!< configWhat + " + " + the layer's file name

	/** Reads the run list and the configs and checks everything a job will
	 * need before any work: every config key and section (errors name the
	 * file and line), every run's rawlog readable with a colour stereo
	 * camera, one camera for all runs (calibration and image size; errors
	 * name both runs and their lines). With `controlPath`, the control's
	 * layered config too (errors name the control file; a layer that sets
	 * nothing is refused: its control would be the baseline). */
	static TEvalInputs Load(
		const std::string& runsPath, const std::vector<std::string>& configPaths, bool checkCameras = true,
		const std::string& controlPath = "");

	bool hasControl() const { return !controlPath.empty(); }
	/** The config as one settings object. */
	const mrpt::config::CConfigFileBase& config() const { return *m_cfg; }
	/** The config a system's jobs run with: the control's layered one for
	 * EvalSystem::Control, else config(); and its text and names. */
	const mrpt::config::CConfigFileBase& configOf(EvalSystem s) const;
	const std::string& configTextOf(EvalSystem s) const;
	const std::string& configWhatOf(EvalSystem s) const;
	/** FNV-1a 64 of the run list, of the configs and of the control's layer: what a plan was made from. */
	std::string runsHash() const;
	std::string configHash() const;
	std::string controlHash() const;

   private:
	std::shared_ptr<mrpt::config::CConfigFileMemory> m_cfg, m_controlCfg;
	void loadControl(const std::string& controlPath, const std::string& cfgNames);
};

/** The jobs for n runs, in the order above (with the control's when `control`). */
std::vector<TEvalJob> makePlan(const std::vector<TRun>& runs, bool control = false);
/** Index of the map job of run i (= i; the control's: n + i), of pair (live, map, system). */
size_t pairJobIndex(size_t nRuns, size_t live, size_t map, EvalSystem s, bool control = false);
/** Map jobs of a plan: N, or 2N with the control. */
size_t mapJobCount(size_t nRuns, bool control);

/** Writes OUTDIR/plan.tsv (the jobs and what they were made from),
 * creating OUTDIR and OUTDIR/jobs. */
void writePlan(const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs);
/** Reads OUTDIR/plan.tsv and checks it was made from these inputs (same run
 * list and configs by content); throws naming what differs, or that there
 * is no plan (run --plan first). Returns the jobs. */
std::vector<TEvalJob> readPlan(const std::string& outDir, const TEvalInputs& in);

struct TJobOptions
{
	int threads = 0;  //!< threads of one localisation system (0: the config's [localise] threads)
	/** Log level of the survey and the localisation (warnings of the VO). */
	mrpt::system::VerbosityLevel verbosity = mrpt::system::LVL_ERROR;
};

/** Runs one job, writing OUTDIR/jobs/<job.name>/ as a whole (replacing an
 * earlier one) or not at all. A pair job whose map is missing or does not
 * load throws naming the map job to run. Returns the job's wall time [s]. */
double runJob(const std::string& outDir, const TEvalInputs& in, const TEvalJob& job, const TJobOptions& o = {});

/** Progress of runAll: jobs done, their total, wall time so far [s], the
 * job that just finished. */
using ProgressFn = std::function<void(size_t done, size_t total, double elapsed_s, const TEvalJob& job)>;

/** Every job of the plan on `workers` threads (a pair starts once its map
 * is done); the first failure stops the pool (jobs running finish) and is
 * thrown naming the job. Returns each job's wall time [s], by job index. */
std::vector<double> runAll(
	const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs, int workers,
	const TJobOptions& o, const ProgressFn& progress = {});

/** What merge() produced, for the command to print. */
struct TMergeResult
{
	std::string table1Markdown;
	std::string summaryText;  //!< ground truth and blind distances, a few lines
};

/** Combines the job outputs (OUTDIR/jobs/...) into OUTDIR: table1.md, table1.csv, summary.md,
 * eval.json, timing.json, figures_inputs.tsv and pairs/, all committed
 * together (io::OutputTransaction). Missing or unreadable job outputs are
 * an error naming every such job. `wall_s` (< 0: unknown) goes to
 * timing.json with the jobs' own times. */
TMergeResult merge(
	const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs, double wall_s = -1);

}  // namespace shadyloc::eval
