/* ShadyLoc — the leave-one-out evaluation: inputs, plan, jobs, the worker
 * pool (docs/evaluation.md). The merge is in EvalMerge.cpp. */
#include <shadyloc/core/ConfigLocation.h>
#include <shadyloc/core/Settings.h>
#include <shadyloc/eval/LeaveOneOut.h>
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/eval/LocaliseOutputs.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/FileHash.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/localisation/LocaliseRun.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/survey/SurveyRun.h>

#include "EvalRecords.h"
#include "Json.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <regex>
#include <sstream>
#include <thread>

namespace shadyloc::eval
{
namespace fs = std::filesystem;
using io::fnv1a64;
using io::fnv1a64File;

const char* toString(EvalSystem s) { return s == EvalSystem::Baseline ? "baseline" : "combined"; }

std::vector<std::string> localisersOf(EvalSystem s)
{
	if (s == EvalSystem::Baseline) return {"mono"};
	return {"mono", "invariant"};
}

namespace
{
bool sameCalib(const geometry::TStereoCalib& a, const geometry::TStereoCalib& b)
{
	const auto eq = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x)); };
	return eq(a.fx, b.fx) && eq(a.fy, b.fy) && eq(a.cx, b.cx) && eq(a.cy, b.cy) && eq(a.cxR, b.cxR) &&
		   eq(a.baseline, b.baseline);
}

struct TCamera
{
	geometry::TStereoCalib calib;
	int width = 0, height = 0;
	std::string label;
};

/** The stereo camera of a run, from its first frame, as the localisation
 * reads it: the config's channels, read from a filtered run or made from
 * colour (nothing is made here: only the calibration is looked at). */
TCamera cameraOf(const std::string& listPath, const TRun& r, const std::vector<filters::TChannel>& channels)
{
	const std::string at = runWhere(listPath, r) + ": '" + r.rawlogPath + "'";
	TCamera c;
	try
	{
		filters::TChannelFrameSourceOptions so;
		so.makeChannels = false;
		filters::ChannelFrameSource src(r.rawlogPath, channels, so);
		filters::TChannelFrame f;
		if (!src.next(f)) throw std::runtime_error(src.noFramesMessage());
		c.label = f.camera;
		c.calib = f.calib;
		c.width = f.size.width;
		c.height = f.size.height;
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(at + ": " + e.what());
	}
	return c;
}

std::string describeCamera(const TCamera& c)
{
	std::ostringstream s;
	s << c.width << "x" << c.height << " px, " << c.calib.asString();
	return s.str();
}

std::string jobsDir(const std::string& outDir) { return (fs::path(outDir) / "jobs").string(); }
std::string jobDir(const std::string& outDir, const TEvalJob& j) { return (fs::path(outDir) / "jobs" / j.name).string(); }

/** "job 5 (live 'a' against the map of 'b', baseline)". */
std::string jobWhat(const std::vector<TRun>& runs, const TEvalJob& j)
{
	if (j.isMap) return "job " + std::to_string(j.index) + " (map of run '" + runs[j.run].name + "')";
	return "job " + std::to_string(j.index) + " (live run '" + runs[j.run].name + "' against the map of '" +
		   runs[j.map].name + "', " + toString(j.system) + ")";
}

std::string jobCommand(const TEvalInputs& in, const std::string& outDir, size_t k)
{
	std::string cmd = "shadyloc eval --runs " + in.runsPath + " -o " + outDir;
	for (const auto& c : in.configPaths) cmd += " -c " + c;
	return cmd + " --job " + std::to_string(k);
}

/** job_timing.json: the job's wall time, one line (the merge gathers them into timing.json). */
void writeJobTime(const std::string& dir, double wall_s)
{
	const Json doc = {{"format", "shadyloc eval job timing"}, {"version", 1}, {"wall_s", fixedNumber(wall_s, 3)}};
	io::writeTextFile((fs::path(dir) / "job_timing.json").string(), writeJson(doc, {}));
}

double runMapJob(const std::string& outDir, const TEvalInputs& in, const TEvalJob& job, const TJobOptions& o)
{
	const auto t0 = std::chrono::steady_clock::now();
	const TRun& run = in.runs[job.run];
	survey::TSurveyRunOptions so;
	so.runName = run.name;
	so.configName = in.configWhat;
	if (run.hasGt())
	{
		so.gt = io::readTum(run.gtPath);
		so.gtName = run.gtPath;
	}
	CKeyframeMap::Ptr map;
	survey::TSurveyStats st;
	try
	{
		survey::CSurveyRun sr(run.rawlogPath, in.config(), so);
		sr.setMinLoggingLevel(o.verbosity);
		for (const auto& w : sr.warnings()) sr.logStr(mrpt::system::LVL_WARN, w);
		map = sr.run();
		st = sr.stats();
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(runWhere(in.runsPath, run) + ": survey: " + e.what());
	}
	io::OutputTransaction tx;
	tx.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	tx.addInput(run.rawlogPath, "rawlog of run '" + run.name + "'");
	const std::string dir = tx.addDirectory(jobDir(outDir, job), "output of " + jobWhat(in.runs, job), "shadyloc eval job output");
	map->saveToFile((fs::path(dir) / "map.kfmap").string());
	TMapRecord rec;
	rec.run = run.name;
	rec.frames = st.frames;
	rec.keyframes = map->keyframeCount();
	rec.gt_keyframes = st.gtKeyframes;
	rec.breaks = st.breaks;
	rec.path_m = map->pathLength();
	writeMapRecord((fs::path(dir) / "map.tsv").string(), rec);
	const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	writeJobTime(dir, wall);
	tx.commit();
	return wall;
}

/** The map a pair job localises against, or an error naming the map job to run (again). */
CKeyframeMap::Ptr loadPairMap(const std::string& outDir, const TEvalInputs& in, const TEvalJob& job, const std::string& mapFile)
{
	const std::string& name = in.runs[job.map].name;
	const std::string what = jobWhat(in.runs, job), redo = jobCommand(in, outDir, job.map);
	if (!fs::exists(mapFile))
		throw std::runtime_error(
			what + ": the map of run '" + name + "' is missing ('" + mapFile + "'): run map job " +
			std::to_string(job.map) + " first (" + redo + ")");
	try
	{
		return CKeyframeMap::LoadFromFile(mapFile);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(
			what + ": the map of run '" + name + "' ('" + mapFile + "', from map job " + std::to_string(job.map) +
			") fails to load: " + e.what() + "; run map job " + std::to_string(job.map) + " again (" + redo + ")");
	}
}

/** A pair's localised run, evaluated. */
struct TPairRun
{
	Updates ups;
	TEvaluation ev;
	localisation::TSystemOptions sys;
};

TPairRun localisePair(
	const TEvalInputs& in, const TEvalJob& job, CKeyframeMap::Ptr map, const std::string& mapRel,
	const std::optional<io::Trajectory>& gt, const TJobOptions& o)
{
	localisation::TLocaliseRunOptions ro;
	ro.localisers = localisersOf(job.system);
	ro.threads = o.threads;
	ro.configWhat = in.configWhat;
	TPairRun r;
	try
	{
		localisation::CLocaliseRun lr(in.config(), map, mapRel, in.runs[job.run].rawlogPath, ro);
		lr.system().setMinLoggingLevel(o.verbosity);
		if (gt) lr.enableOracle(*gt);
		r.ups = lr.run();
		r.sys = lr.system().options();
		r.ev = evaluate(r.ups, *map, gt ? &*gt : nullptr);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(jobWhat(in.runs, job) + ": " + e.what());
	}
	return r;
}

/** summary.json's provenance of a pair: paths as the run list writes them
 * and the map relative to OUTDIR, so the summary does not depend on where
 * the evaluation ran. */
TLocaliseProvenance pairProvenance(const TEvalInputs& in, const TRun& live, const std::string& mapRel, const std::string& mapFile, bool gt)
{
	TLocaliseProvenance prov;
	prov.program = "shadyloc eval";
	prov.buildCommit = in.buildCommit;
	prov.configWhat = in.configWhat;
	prov.configText = in.configText;
	prov.mapPath = mapRel;
	prov.mapHash = fnv1a64File(mapFile);
	prov.livePath = live.rawlog;
	prov.liveHash = fnv1a64File(live.rawlogPath);
	if (gt)
	{
		prov.gtPath = live.gt;
		prov.gtHash = fnv1a64File(live.gtPath);
	}
	return prov;
}

double runPairJob(const std::string& outDir, const TEvalInputs& in, const TEvalJob& job, const TJobOptions& o)
{
	const auto t0 = std::chrono::steady_clock::now();
	const TRun& live = in.runs[job.run];
	const TRun& mapRun = in.runs[job.map];
	const std::string mapRel = "jobs/map_" + mapRun.name + "/map.kfmap";
	const std::string mapFile = (fs::path(outDir) / mapRel).string();
	const CKeyframeMap::Ptr map = loadPairMap(outDir, in, job, mapFile);
	// Ground truth only where both runs have it: the map's keyframes carry
	// the survey's, the live frames the live run's.
	std::optional<io::Trajectory> gt;
	if (live.hasGt() && mapRun.hasGt()) gt = io::readTum(live.gtPath);
	const TPairRun r = localisePair(in, job, map, mapRel, gt, o);

	io::OutputTransaction tx;
	tx.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	tx.addInput(live.rawlogPath, "rawlog of run '" + live.name + "'");
	tx.addInput(mapFile, "map of run '" + mapRun.name + "'");
	const std::string dir =
		tx.addDirectory(jobDir(outDir, job), "output of " + jobWhat(in.runs, job), "shadyloc eval job output");
	writeLocaliseOutputs(dir, r.ups, r.ev, *map, r.sys, pairProvenance(in, live, mapRel, mapFile, gt.has_value()));
	writePairRecord((fs::path(dir) / "pair.tsv").string(), makePairRecord(live.name, mapRun.name, job.system, r.ups, r.ev));
	const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	writeJobTime(dir, wall);
	tx.commit();
	return wall;
}
}  // namespace

// ---------------------------------------------------------------------------
TEvalInputs TEvalInputs::Load(
	const std::string& runsPath, const std::vector<std::string>& configPaths, bool checkCameras)
{
	TEvalInputs in;
	in.runsPath = runsPath;
	in.runs = readRunList(runsPath);
	in.configPaths = configPaths;
	for (const auto& c : configPaths)
		if (!fs::is_regular_file(c)) throw std::runtime_error("config file '" + c + "' does not exist");
	in.configText = core::layeredConfigText(configPaths);
	// Names, not paths: the provenance does not depend on where it ran.
	for (const auto& c : configPaths)
		in.configWhat += (in.configWhat.empty() ? "" : " + ") + fs::path(c).filename().string();
	if (in.configWhat.empty()) in.configWhat = "(no config)";
	in.m_cfg = std::make_shared<mrpt::config::CConfigFileMemory>(in.configText);
	const std::string cfgNames = [&] {
		std::string s;
		for (const auto& c : configPaths) s += (s.empty() ? "" : " + ") + c;
		return s.empty() ? std::string("(no config)") : s;
	}();
	// Every options struct a job reads, before any job runs.
	try
	{
		localisation::checkLocaliseConfig(*in.m_cfg, localisersOf(EvalSystem::Baseline), cfgNames);
		localisation::checkLocaliseConfig(*in.m_cfg, localisersOf(EvalSystem::Combined), cfgNames);
		TKeyframeMapOptions mo;
		if (in.m_cfg->sectionExists("map")) mo.loadFromConfigFile(*in.m_cfg, "map");
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(core::configError(configPaths, cfgNames, e.what()));
	}
	if (checkCameras)
	{
		// One camera for every run: a map refuses live data whose descriptor
		// parameters differ, and pairs of different cameras are not the
		// paper's comparison.
		std::vector<filters::TChannel> channels;
		for (const auto& ch : localisation::CLocalisationSystem::SetupFromConfig(*in.m_cfg, {}, 0, cfgNames).channels)
			channels.push_back(ch.channel);
		std::vector<TCamera> cams;
		for (const auto& r : in.runs) cams.push_back(cameraOf(runsPath, r, channels));
		for (size_t i = 1; i < cams.size(); i++)
			if (!sameCalib(cams[i].calib, cams[0].calib) || cams[i].width != cams[0].width ||
				cams[i].height != cams[0].height)
				throw std::runtime_error(
					runWhere(runsPath, in.runs[i]) + ": its camera ('" + in.runs[i].rawlogPath + "': " +
					describeCamera(cams[i]) + ") differs from run '" + in.runs[0].name + "''s (line " +
					std::to_string(in.runs[0].line) + ", '" + in.runs[0].rawlogPath + "': " + describeCamera(cams[0]) +
					"); a leave-one-out evaluation compares runs of one camera");
	}
	return in;
}

std::string TEvalInputs::runsHash() const { return fnv1a64File(runsPath); }
std::string TEvalInputs::configHash() const { return fnv1a64(configText); }

std::vector<TEvalJob> makePlan(const std::vector<TRun>& runs)
{
	const size_t n = runs.size();
	std::vector<TEvalJob> jobs;
	for (size_t i = 0; i < n; i++)
	{
		TEvalJob j;
		j.index = jobs.size();
		j.isMap = true;
		j.run = i;
		j.name = "map_" + runs[i].name;
		jobs.push_back(j);
	}
	for (size_t i = 0; i < n; i++)
		for (size_t m = 0; m < n; m++)
		{
			if (m == i) continue;
			for (const EvalSystem s : {EvalSystem::Baseline, EvalSystem::Combined})
			{
				TEvalJob j;
				j.index = jobs.size();
				j.run = i;
				j.map = m;
				j.system = s;
				j.name = "pair_" + runs[i].name + "__" + runs[m].name + "__" + toString(s);
				jobs.push_back(j);
			}
		}
	return jobs;
}

size_t pairJobIndex(size_t n, size_t live, size_t map, EvalSystem s)
{
	const size_t other = map - (map > live ? 1 : 0);
	return n + 2 * (live * (n - 1) + other) + (s == EvalSystem::Combined ? 1 : 0);
}

void writePlan(const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs)
{
	std::error_code ec;
	fs::create_directories(jobsDir(outDir), ec);
	if (ec || !fs::is_directory(jobsDir(outDir)))
		throw std::runtime_error("output '" + outDir + "': cannot create '" + jobsDir(outDir) + "'");
	std::ostringstream s;
	s << "# shadyloc eval plan v" << kPlanVersion << "\n# runs_fnv1a64\t" << in.runsHash() << "\n# config_fnv1a64\t"
	  << in.configHash() << "\n# maps\t0\t" << in.runs.size() - 1 << "\n# pairs\t" << in.runs.size() << "\t"
	  << jobs.size() - 1 << "\njob\tkind\trun\tmap\tsystem\tname\n";
	for (const auto& j : jobs)
		s << j.index << '\t' << (j.isMap ? "map" : "pair") << '\t' << in.runs[j.run].name << '\t'
		  << (j.isMap ? "-" : in.runs[j.map].name) << '\t' << (j.isMap ? "-" : toString(j.system)) << '\t' << j.name
		  << '\n';
	io::writeTextFile((fs::path(outDir) / "plan.tsv").string(), s.str());
}

std::vector<TEvalJob> readPlan(const std::string& outDir, const TEvalInputs& in)
{
	const std::string path = (fs::path(outDir) / "plan.tsv").string();
	if (!fs::exists(path))
		throw std::runtime_error(
			"'" + path + "' does not exist: make the plan first (shadyloc eval --runs " + in.runsPath + " -o " + outDir +
			" ... --plan)");
	std::ifstream f(path);
	std::string line, runsHash, cfgHash;
	std::vector<std::string> rows;
	int n = 0;
	while (std::getline(f, line))
	{
		n++;
		if (n == 1 && line != "# shadyloc eval plan v" + std::to_string(kPlanVersion))
			throw std::runtime_error(
				path + ":1: not a shadyloc eval plan of version " + std::to_string(kPlanVersion) + " ('" + line + "')");
		if (line.rfind("# runs_fnv1a64\t", 0) == 0) runsHash = line.substr(15);
		if (line.rfind("# config_fnv1a64\t", 0) == 0) cfgHash = line.substr(17);
		if (!line.empty() && line[0] != '#' && line.rfind("job\t", 0) != 0) rows.push_back(line);
	}
	if (n == 0) throw std::runtime_error(path + ": empty; make the plan again (--plan)");
	if (runsHash != in.runsHash())
		throw std::runtime_error(
			path + ": made from another run list than '" + in.runsPath + "' (contents differ): make the plan again (--plan)");
	if (cfgHash != in.configHash())
		throw std::runtime_error(
			path + ": made with other configs than " + (in.configPaths.empty() ? std::string("none") : in.configWhat) +
			" (contents differ): make the plan again (--plan), or give the same -c files");
	const auto jobs = makePlan(in.runs);
	if (rows.size() != jobs.size())
		throw std::runtime_error(
			path + ": " + std::to_string(rows.size()) + " jobs, but the run list makes " + std::to_string(jobs.size()) +
			": make the plan again (--plan)");
	for (size_t k = 0; k < jobs.size(); k++)
	{
		std::istringstream r(rows[k]);
		std::vector<std::string> c;
		for (std::string w; std::getline(r, w, '\t');) c.push_back(w);
		if (c.size() != 6 || c[0] != std::to_string(k) || c[5] != jobs[k].name)
			throw std::runtime_error(path + ": job " + std::to_string(k) + " is not '" + jobs[k].name + "': make the plan again (--plan)");
	}
	return jobs;
}

double runJob(const std::string& outDir, const TEvalInputs& in, const TEvalJob& job, const TJobOptions& o)
{
	if (!fs::is_directory(jobsDir(outDir)))
		throw std::runtime_error("'" + jobsDir(outDir) + "' does not exist: make the plan first (--plan)");
	return job.isMap ? runMapJob(outDir, in, job, o) : runPairJob(outDir, in, job, o);
}

std::vector<double> runAll(
	const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs, int workers,
	const TJobOptions& o, const ProgressFn& progress)
{
	const auto t0 = std::chrono::steady_clock::now();
	std::vector<double> times(jobs.size(), 0);
	std::vector<char> done(jobs.size(), 0);
	std::mutex mx;
	std::condition_variable cv;
	size_t next = 0, finished = 0;
	bool failed = false;
	std::string error;
	const auto worker = [&] {
		for (;;)
		{
			size_t k;
			{
				std::unique_lock<std::mutex> lock(mx);
				if (failed || next >= jobs.size()) return;
				k = next++;
				// Maps come first in the plan; a pair waits for its map.
				if (!jobs[k].isMap)
				{
					cv.wait(lock, [&] { return failed || done[jobs[k].map]; });
					if (failed) return;
				}
			}
			try
			{
				const double t = runJob(outDir, in, jobs[k], o);
				std::lock_guard<std::mutex> lock(mx);
				times[k] = t;
				done[k] = 1;
				finished++;
				if (progress)
					progress(
						finished, jobs.size(),
						std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), jobs[k]);
			}
			catch (const std::exception& e)
			{
				std::lock_guard<std::mutex> lock(mx);
				if (!failed) error = e.what();
				failed = true;
			}
			cv.notify_all();
		}
	};
	const int n = std::max(1, std::min<int>(workers, static_cast<int>(jobs.size())));
	std::vector<std::thread> pool;
	for (int i = 1; i < n; i++) pool.emplace_back(worker);
	worker();
	for (auto& t : pool) t.join();
	if (failed) throw std::runtime_error(error);
	return times;
}

}  // namespace shadyloc::eval
