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

const char* toString(EvalSystem s)
{
	switch (s)
	{
		case EvalSystem::Baseline: return "baseline";
		case EvalSystem::Combined: return "combined";
		case EvalSystem::Control: return "control";
	}
	return "?";
}

std::vector<std::string> localisersOf(EvalSystem s)
{
	// The control is the baseline's localiser; only its config differs.
	if (s == EvalSystem::Combined) return {"mono", "invariant"};
	return {"mono"};
}

std::vector<EvalSystem> systemsOf(bool control)
{
	if (control) return {EvalSystem::Baseline, EvalSystem::Combined, EvalSystem::Control};
	return {EvalSystem::Baseline, EvalSystem::Combined};
}

std::string mapJobName(const std::string& run, EvalSystem s)
{
	// "control_" leads: no run name makes "map_..." collide with it.
	return (s == EvalSystem::Control ? "control_map_" : "map_") + run;
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
	if (j.isMap)
		return "job " + std::to_string(j.index) + " (" + (j.system == EvalSystem::Control ? "control's " : "") +
			   "map of run '" + runs[j.run].name + "')";
	return "job " + std::to_string(j.index) + " (live run '" + runs[j.run].name + "' against the map of '" +
		   runs[j.map].name + "', " + toString(j.system) + ")";
}

std::string jobCommand(const TEvalInputs& in, const std::string& outDir, size_t k)
{
	std::string cmd = "shadyloc eval --runs " + in.runsPath + " -o " + outDir;
	for (const auto& c : in.configPaths) cmd += " -c " + c;
	if (in.hasControl()) cmd += " --control " + in.controlPath;
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
	so.configName = in.configWhatOf(job.system);
	if (run.hasGt())
	{
		so.gt = io::readTum(run.gtPath);
		so.gtName = run.gtPath;
	}
	CKeyframeMap::Ptr map;
	survey::TSurveyStats st;
	try
	{
		survey::SurveyRun sr(run.rawlogPath, in.configOf(job.system), so);
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
	const std::string what = jobWhat(in.runs, job), redo = jobCommand(in, outDir, job.mapJob);
	const std::string mapJob = std::to_string(job.mapJob);
	if (!fs::exists(mapFile))
		throw std::runtime_error(
			what + ": the map of run '" + name + "' is missing ('" + mapFile + "'): run map job " + mapJob +
			" first (" + redo + ")");
	try
	{
		return CKeyframeMap::LoadFromFile(mapFile);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(
			what + ": the map of run '" + name + "' ('" + mapFile + "', from map job " + mapJob + ") fails to load: " +
			e.what() + "; run map job " + mapJob + " again (" + redo + ")");
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
	ro.configWhat = in.configWhatOf(job.system);
	TPairRun r;
	try
	{
		localisation::LocaliseRun lr(in.configOf(job.system), map, mapRel, in.runs[job.run].rawlogPath, ro);
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
TLocaliseProvenance pairProvenance(
	const TEvalInputs& in, const TEvalJob& job, const std::string& mapRel, const std::string& mapFile, bool gt)
{
	const TRun& live = in.runs[job.run];
	TLocaliseProvenance prov;
	prov.program = "shadyloc eval";
	prov.buildCommit = in.buildCommit;
	prov.configWhat = in.configWhatOf(job.system);
	prov.configText = in.configTextOf(job.system);
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
	const std::string mapRel = "jobs/" + mapJobName(mapRun.name, job.system) + "/map.kfmap";
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
	writeLocaliseOutputs(dir, r.ups, r.ev, *map, r.sys, pairProvenance(in, job, mapRel, mapFile, gt.has_value()));
	writePairRecord((fs::path(dir) / "pair.tsv").string(), makePairRecord(live.name, mapRun.name, job.system, r.ups, r.ev));
	const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	writeJobTime(dir, wall);
	tx.commit();
	return wall;
}
}  // namespace

// ---------------------------------------------------------------------------
TEvalInputs TEvalInputs::Load(
	const std::string& runsPath, const std::vector<std::string>& configPaths, bool checkCameras,
	const std::string& controlPath)
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
	if (!controlPath.empty()) in.loadControl(controlPath, cfgNames);
	if (checkCameras)
	{
		// One camera for every run: a map refuses live data whose descriptor
		// parameters differ, and pairs of different cameras are not the
		// paper's comparison.
		std::vector<filters::TChannel> channels;
		for (const auto& ch : localisation::LocalisationSystem::SetupFromConfig(*in.m_cfg, {}, 0, cfgNames).channels)
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

namespace
{
/** Keys the layer sets, counted over its sections. */
size_t keysSet(const mrpt::config::CConfigFileBase& c)
{
	std::vector<std::string> sections, keys;
	c.getAllSections(sections);
	size_t n = 0;
	for (const auto& sec : sections)
	{
		c.getAllKeys(sec, keys);
		n += keys.size();
	}
	return n;
}
}  // namespace

void TEvalInputs::loadControl(const std::string& path, const std::string& cfgNames)
{
	const std::string what = "--control '" + path + "'";
	if (!fs::is_regular_file(path)) throw std::runtime_error(what + ": the control's config does not exist");
	try
	{
		controlLayerText = core::layeredConfigText({path});
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(what + ": " + e.what());
	}
	if (keysSet(mrpt::config::CConfigFileMemory(controlLayerText)) == 0)
		throw std::runtime_error(
			what + ": sets no key, so the control would be the baseline; give the settings it changes (e.g. "
				   "config/control_budget.ini)");
	std::vector<std::string> files = configPaths;
	files.push_back(path);
	controlPath = path;
	controlText = core::layeredConfigText(files);
	controlWhat = configWhat == "(no config)" ? fs::path(path).filename().string()
											  : configWhat + " + " + fs::path(path).filename().string();
	m_controlCfg = std::make_shared<mrpt::config::CConfigFileMemory>(controlText);
	// What the control's map and pair jobs read, strictly, before any job runs.
	try
	{
		localisation::checkLocaliseConfig(*m_controlCfg, localisersOf(EvalSystem::Control), cfgNames + " + " + path);
		TKeyframeMapOptions mo;
		if (m_controlCfg->sectionExists("map")) mo.loadFromConfigFile(*m_controlCfg, "map");
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(what + ": " + core::configError(files, cfgNames + " + " + path, e.what()));
	}
}

const mrpt::config::CConfigFileBase& TEvalInputs::configOf(EvalSystem s) const
{
	return s == EvalSystem::Control ? *m_controlCfg : *m_cfg;
}
const std::string& TEvalInputs::configTextOf(EvalSystem s) const
{
	return s == EvalSystem::Control ? controlText : configText;
}
const std::string& TEvalInputs::configWhatOf(EvalSystem s) const
{
	return s == EvalSystem::Control ? controlWhat : configWhat;
}

std::string TEvalInputs::runsHash() const { return fnv1a64File(runsPath); }
std::string TEvalInputs::configHash() const { return fnv1a64(configText); }
std::string TEvalInputs::controlHash() const { return fnv1a64(controlLayerText); }

namespace
{
/** The map job of run i: the shared map, or the control's own. */
TEvalJob mapJob(const std::vector<TRun>& runs, size_t i, EvalSystem s, size_t index)
{
	TEvalJob j;
	j.index = index;
	j.isMap = true;
	j.run = i;
	j.system = s;
	j.name = mapJobName(runs[i].name, s);
	return j;
}
}  // namespace

size_t mapJobCount(size_t n, bool control) { return control ? 2 * n : n; }

std::vector<TEvalJob> makePlan(const std::vector<TRun>& runs, bool control)
{
	const size_t n = runs.size();
	std::vector<TEvalJob> jobs;
	for (size_t i = 0; i < n; i++) jobs.push_back(mapJob(runs, i, EvalSystem::Baseline, jobs.size()));
	if (control)
		for (size_t i = 0; i < n; i++) jobs.push_back(mapJob(runs, i, EvalSystem::Control, jobs.size()));
	for (size_t i = 0; i < n; i++)
		for (size_t m = 0; m < n; m++)
		{
			if (m == i) continue;
			for (const EvalSystem s : systemsOf(control))
			{
				TEvalJob j;
				j.index = jobs.size();
				j.run = i;
				j.map = m;
				// The combined system localises on the baseline's map.
				j.mapJob = s == EvalSystem::Control ? n + m : m;
				j.system = s;
				j.name = "pair_" + runs[i].name + "__" + runs[m].name + "__" + toString(s);
				jobs.push_back(j);
			}
		}
	return jobs;
}

size_t pairJobIndex(size_t n, size_t live, size_t map, EvalSystem s, bool control)
{
	const size_t other = map - (map > live ? 1 : 0);
	const size_t systems = control ? 3 : 2;
	return mapJobCount(n, control) + systems * (live * (n - 1) + other) + static_cast<size_t>(s);
}

void writePlan(const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs)
{
	std::error_code ec;
	fs::create_directories(jobsDir(outDir), ec);
	if (ec || !fs::is_directory(jobsDir(outDir)))
		throw std::runtime_error("output '" + outDir + "': cannot create '" + jobsDir(outDir) + "'");
	const size_t maps = mapJobCount(in.runs.size(), in.hasControl());
	std::ostringstream s;
	s << "# shadyloc eval plan v" << kPlanVersion << "\n# runs_fnv1a64\t" << in.runsHash() << "\n# config_fnv1a64\t"
	  << in.configHash() << "\n";
	// Only with a control, so that a plan without one keeps its bytes.
	if (in.hasControl()) s << "# control_fnv1a64\t" << in.controlHash() << "\n";
	s << "# maps\t0\t" << maps - 1 << "\n# pairs\t" << maps << "\t" << jobs.size() - 1
	  << "\njob\tkind\trun\tmap\tsystem\tname\n";
	for (const auto& j : jobs)
	{
		// A map job's system column names the control's maps only.
		const char* system = j.isMap ? (j.system == EvalSystem::Control ? "control" : "-") : toString(j.system);
		s << j.index << '\t' << (j.isMap ? "map" : "pair") << '\t' << in.runs[j.run].name << '\t'
		  << (j.isMap ? "-" : in.runs[j.map].name) << '\t' << system << '\t' << j.name << '\n';
	}
	io::writeTextFile((fs::path(outDir) / "plan.tsv").string(), s.str());
}

namespace
{
/** The plan's control (its layer's hash, "" without) must be the one given now. */
void checkPlanControl(const std::string& path, const TEvalInputs& in, const std::string& planHash)
{
	if (planHash.empty() && in.hasControl())
		throw std::runtime_error(
			path + ": made without --control, given --control '" + in.controlPath +
			"' now: make the plan again (--plan) with it, or leave it out");
	if (!planHash.empty() && !in.hasControl())
		throw std::runtime_error(path + ": made with --control: give the same --control file");
	if (!planHash.empty() && planHash != in.controlHash())
		throw std::runtime_error(
			path + ": made with another control than '" + in.controlPath +
			"' (contents differ): make the plan again (--plan), or give the same --control file");
}
}  // namespace

std::vector<TEvalJob> readPlan(const std::string& outDir, const TEvalInputs& in)
{
	const std::string path = (fs::path(outDir) / "plan.tsv").string();
	if (!fs::exists(path))
		throw std::runtime_error(
			"'" + path + "' does not exist: make the plan first (shadyloc eval --runs " + in.runsPath + " -o " + outDir +
			" ... --plan)");
	std::ifstream f(path);
	std::string line, runsHash, cfgHash, controlHash;
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
		if (line.rfind("# control_fnv1a64\t", 0) == 0) controlHash = line.substr(18);
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
	checkPlanControl(path, in, controlHash);
	const auto jobs = makePlan(in.runs, in.hasControl());
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
					cv.wait(lock, [&] { return failed || done[jobs[k].mapJob]; });
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
