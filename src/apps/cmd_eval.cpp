/* shadyloc eval: the paper's leave-one-out evaluation over N runs, in one
 * process on a worker pool or as independent jobs on a cluster
 * (docs/evaluation.md). */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/LeaveOneOut.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "shadyloc_commit.h"  // SHADYLOC_GIT_COMMIT, written at build time (cmake/WriteCommit.cmake)

namespace cmd_eval
{
using namespace shadyloc;
namespace fs = std::filesystem;

std::string clock(double s)
{
	const long t = std::lround(std::max(0.0, s));
	char b[32];
	if (t >= 3600)
		std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
	else
		std::snprintf(b, sizeof b, "%ld:%02ld", t / 60, t % 60);
	return b;
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"The paper's evaluation: exhaustive leave-one-out over the runs of RUNS.txt. Each run is surveyed once "
		"into a map; each run is localised against the map of every other run with the baseline system alone "
		"(mono) and with the combined system (mono,invariant), separately. Without --plan/--job/--merge it runs "
		"every job on a worker pool (-j) and merges. For a cluster: --plan writes OUTDIR/plan.tsv and prints the "
		"job ranges ('maps 0 <N-1>', 'pairs <N> <last>'), --job K runs one job (maps before pairs), --merge "
		"combines them. With --control INI, a third system: the baseline run on its own maps with INI layered "
		"over the configs (a budget-matched control, config/control_budget.ini). Outputs: table1.md/.csv (Table I), "
		"summary.md, eval.json, timing.json, figures_inputs.tsv, pairs/ (docs/evaluation.md).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> runsArg(
		"", "runs", "run list: one run a line, 'name rawlog [ground_truth.tum]' (docs/evaluation.md)", true, "",
		"RUNS.txt", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "output directory (created if missing)", true, "", "OUTDIR", cmd);
	TCLAP::MultiArg<std::string> cfgArgs(
		"c", "config",
		"options .ini, may be repeated (sections of all files together): the survey's ([vo], [features], [map], "
		"channels) and the localisation's ([localise], [localiser], [localiser.<channel>])",
		false, "ini", cmd);
	TCLAP::ValueArg<std::string> controlArg(
		"", "control",
		"a third system, the control: the baseline (mono) with this .ini layered after the -c files, on maps of "
		"its own surveyed with it (e.g. config/control_budget.ini: the combined system's feature budget spent on "
		"monochrome). Give it again with --job and --merge",
		false, "", "INI", cmd);
	shadyloc::apps::NumberArg<int> jobsArg(
		cli, "j", "workers", "worker threads of the in-process run (default: the number of cores)", 0, "N", 1, 1024);
	TCLAP::SwitchArg planArg("", "plan", "write OUTDIR/plan.tsv and print the job ranges; run nothing", cmd);
	shadyloc::apps::NumberArg<long> jobArg(cli, "", "job", "run job K of the plan only", -1, "K", 0, 1L << 40);
	TCLAP::SwitchArg mergeArg("", "merge", "combine OUTDIR/jobs/* into the outputs", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no progress output", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	const int modes = int(planArg.getValue()) + int(jobArg.isSet()) + int(mergeArg.getValue());
	if (modes > 1) return cli.usageError("--plan, --job and --merge: give one at most");
	if (jobsArg.isSet() && modes) return cli.usageError("-j is for the in-process run (without --plan/--job/--merge)");
	const bool talk = !quiet.getValue();
	const std::string outDir = out.getValue();

	if (jobArg.isSet() || mergeArg.getValue())
	{
		// The plan's checks (configs, cameras) were made when it was written.
		auto in = eval::TEvalInputs::Load(runsArg.getValue(), cfgArgs.getValue(), false, controlArg.getValue());
		in.buildCommit = SHADYLOC_GIT_COMMIT;
		const auto jobs = eval::readPlan(outDir, in);
		if (mergeArg.getValue())
		{
			const auto r = eval::merge(outDir, in, jobs);
			std::cout << r.table1Markdown << "\n" << r.summaryText << "\n-> " << outDir << "\n";
			return 0;
		}
		const auto k = static_cast<size_t>(jobArg.getValue());
		if (k >= jobs.size())
			throw std::runtime_error(
				"--job " + std::to_string(k) + ": the plan in '" + outDir + "' has jobs 0.." + std::to_string(jobs.size() - 1));
		eval::TJobOptions jo;
		if (talk) jo.verbosity = mrpt::system::LVL_WARN;
		const double s = eval::runJob(outDir, in, jobs[k], jo);
		if (talk)
			std::cout << "job " << k << " (" << jobs[k].name << ") done in " << std::fixed << std::setprecision(1) << s
					  << " s -> " << (fs::path(outDir) / "jobs" / jobs[k].name).string() << "\n";
		return 0;
	}

	auto in = eval::TEvalInputs::Load(runsArg.getValue(), cfgArgs.getValue(), true, controlArg.getValue());
	in.buildCommit = SHADYLOC_GIT_COMMIT;
	const auto jobs = eval::makePlan(in.runs, in.hasControl());
	eval::writePlan(outDir, in, jobs);
	const size_t n = eval::mapJobCount(in.runs.size(), in.hasControl());
	if (planArg.getValue())
	{
		std::cout << "maps 0 " << n - 1 << "\npairs " << n << " " << jobs.size() - 1 << "\n";
		return 0;
	}

	const int workers = jobsArg.isSet() ? jobsArg.getValue() : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
	eval::TJobOptions jo;
	// Parallel jobs: one thread per localisation system (the results do not
	// depend on it); one worker: the config's threads for the channels.
	if (workers > 1) jo.threads = 1;
	const bool tty = ::isatty(STDERR_FILENO);
	if (talk)
		std::cerr << "eval: " << in.runs.size() << " runs -> " << n << " maps + " << jobs.size() - n << " pair jobs on " << workers
				  << " worker" << (workers > 1 ? "s" : "") << " -> " << outDir << "\n";
	const auto t0 = std::chrono::steady_clock::now();
	eval::runAll(outDir, in, jobs, workers, jo, [&](size_t done, size_t total, double el, const eval::TEvalJob& j) {
		if (!talk) return;
		const double eta = done ? el / static_cast<double>(done) * static_cast<double>(total - done) : 0;
		std::ostringstream s;
		s << "eval: " << done << "/" << total << " jobs, elapsed " << clock(el) << ", ETA " << clock(eta) << " ("
		  << j.name << ")";
		if (tty)
			std::cerr << "\r" << std::left << std::setw(100) << s.str() << (done == total ? "\n" : "") << std::flush;
		else
			std::cerr << s.str() << "\n";
	});
	const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	const auto r = eval::merge(outDir, in, jobs, wall);
	std::cout << r.table1Markdown << "\n" << r.summaryText << "\n";
	std::cout << std::fixed << std::setprecision(1) << jobs.size() << " jobs in " << wall << " s on " << workers
			  << " worker" << (workers > 1 ? "s" : "") << " -> " << outDir << "\n";
	return 0;
}

shadyloc::apps::RegisterCommand reg(
	"eval",
	{"leave-one-out evaluation over N runs, Table I (--runs RUNS.txt -o OUTDIR [-c ini]... [--control ini] [-j N] "
	 "[--plan | --job K | --merge])",
	 run});
}  // namespace cmd_eval
