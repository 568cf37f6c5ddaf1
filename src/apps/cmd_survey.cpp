/* shadyloc survey: a dual-channel keyframe map from a survey rawlog. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/core/ConfigLocation.h>
#include <shadyloc/core/Settings.h>
#include <shadyloc/geometry/PoseCovariance.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/localisation/LocaliseRun.h>
#include <shadyloc/survey/AppendExperience.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/survey/SurveyRun.h>
#include <shadyloc/vo/VOConfig.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/system/string_utils.h>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>

namespace cmd_survey
{
using namespace shadyloc;

bool endsWith(const std::string& s, const std::string& suf)
{
	return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

/** Localises the surveyed run against `base` and appends it as a new
 * experience (survey/AppendExperience.h); `base` becomes the output map. */
survey::TAppendReport appendRun(
	const mrpt::config::CConfigFileBase& cfg, const std::string& cfgWhat, const CKeyframeMap::Ptr& base,
	const std::string& basePath, const std::string& rawlog, const CKeyframeMap& runMap, const std::string& runName,
	const std::string& sensorLabel, bool talk)
{
	localisation::TLocaliseRunOptions ro;
	ro.sensorLabel = sensorLabel;
	ro.configWhat = cfgWhat;
	localisation::LocaliseRun lrun(cfg, base, basePath, rawlog, ro);
	if (talk) std::cout << "localising the run against '" << basePath << "' to link it (" << base->runs().size() << " experience(s))" << std::endl;
	std::vector<survey::TRunFix> fixes;
	lrun.run([&](const localisation::TLocalisationUpdate& u) {
		if (u.localised()) fixes.push_back({u.frame, u.kf_id, u.T_kf_live, u.cov});
		if (talk && u.frame % 100 == 0) std::cout << "frame " << u.frame << ": " << fixes.size() << " fixes so far" << std::endl;
	});
	const size_t frames = lrun.updates().size();
	if (talk)
		std::cout << "localised " << fixes.size() << " of " << frames << " frames (" << std::fixed << std::setprecision(1)
				  << 100.0 * fixes.size() / std::max<size_t>(1, frames) << " %)" << std::endl;
	return survey::appendExperience(*base, runMap, runName, fixes);
}

void writeLinksCsv(const std::string& path, const survey::TAppendReport& rep)
{
	std::ofstream f(path);
	f << "map_kf,new_kf,verified,agreeing,x,y,z,sigma_m,err_m,err_deg\n" << std::setprecision(6);
	for (const auto& l : rep.candidates)
	{
		const auto t = l.link.T_a_b.translation();
		f << l.link.a << "," << l.link.b << "," << int(l.verified) << "," << l.agreeing << "," << t.x() << "," << t.y()
		  << "," << t.z() << "," << geometry::translationSigma(l.link.cov) << ",";
		if (l.err_m) f << *l.err_m << "," << *l.err_deg;
		else f << ",";
		f << "\n";
	}
	if (!f) throw std::runtime_error("--links: cannot write '" + path + "'");
}

void printAppendReport(const survey::TAppendReport& rep, const CKeyframeMap& out)
{
	std::vector<double> et, er;
	for (const auto& l : rep.candidates)
		if (l.verified && l.err_m) et.push_back(*l.err_m), er.push_back(*l.err_deg);
	std::cout << "experience '" << rep.run << "': " << rep.keyframes << " keyframes, " << rep.candidates.size()
			  << " candidate links, " << rep.verified() << " verified by a loop with a neighbour; ";
	if (rep.anchored)
		std::cout << "anchored in the frame of '" << rep.frame_of << "' (" << rep.placed_from_other_segment
				  << " keyframes placed from another segment's link, marked predicted)\n";
	else
		std::cout << "too few links: kept in its own frame, linked nowhere (found by the global search only)\n";
	if (!et.empty())
	{
		const auto med = [](std::vector<double> v) {
			std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
			return v[v.size() / 2];
		};
		std::cout << std::fixed << std::setprecision(3) << "verified links against ground truth: median "
				  << med(et) << " m / " << med(er) << " deg, max " << *std::max_element(et.begin(), et.end()) << " m / "
				  << *std::max_element(er.begin(), er.end()) << " deg\n";
	}
	std::cout << "map: " << out.runs().size() << " experiences, " << out.keyframeCount() << " keyframes, "
			  << out.links().size() << " links\n";
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Builds a dual-channel keyframe map (" + std::string(CKeyframeMap::kFileExtension) +
			") from a survey rawlog: the first channel's VO (mono by default) chooses the keyframes, and at each "
			"one the stereo measurements of every channel are stored. A channel is the filter that makes its "
			"images (a section of the config, or the built-in mono / invariant); its frames are the rawlog's "
			"<camera><suffix> observations when it holds them (the filter record says how they were made), "
			"otherwise the colour images filtered on the fly. Map options: the config's [map] section.");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> in("i", "input", "survey rawlog", true, "", "run.rawlog", cmd);
	TCLAP::ValueArg<std::string> out(
		"o", "output", std::string("map file (") + CKeyframeMap::kFileExtension + ")", true, "", "map.kfmap", cmd);
	TCLAP::MultiArg<std::string> cfgArgs(
		"c", "config",
		"options .ini, may be repeated (sections of all files together): [vo], [features], [features.<channel>], the "
		"channel sections [mono] [invariant], [map] (see config/vo.ini); with --append also [localise], [localiser], "
		"[localiser.<channel>] (config/localise_sim.ini)",
		false, "vo.ini", cmd);
	TCLAP::ValueArg<std::string> appendArg(
		"", "append",
		"add the run to this map as a new experience: the output is the map plus the run, linked where the run "
		"localises against the map (the input map is never changed)",
		false, "", "map.kfmap", cmd);
	TCLAP::ValueArg<std::string> linksArg(
		"", "links", "with --append: every candidate link as CSV (verified or not, error against ground truth)", false,
		"", "links.csv", cmd);
	TCLAP::ValueArg<std::string> chArg(
		"", "channels", "channels to store, comma-separated; the first one's VO makes the keyframe chain", false,
		"mono,invariant", "mono,invariant", cmd);
	TCLAP::ValueArg<std::string> bridgeArg(
		"", "bridge",
		"channel whose VO bridges the chain VO's breaks (its motion links the segment on): a stored channel after "
		"the first, 'auto' (the second) or 'none'",
		false, "auto", "channel", cmd);
	TCLAP::ValueArg<std::string> gtArg("", "gt", "ground truth (TUM), stored beside the keyframes", false, "", "run.tum", cmd);
	TCLAP::ValueArg<std::string> runName("", "run-name", "survey run name (default: the rawlog's stem): letters, digits, '_', '-' and '.' only", false, "", "name", cmd);
	TCLAP::ValueArg<std::string> label(
		"", "label", "sensor label of the colour stereo camera (default: the first one found)", false, "", "label", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no option dump or progress", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	const std::string inPath = in.getValue(), outPath = out.getValue();
	const bool append = appendArg.isSet();
	if (!endsWith(outPath, CKeyframeMap::kFileExtension))
		throw std::runtime_error("output '" + outPath + "': map files end in " + CKeyframeMap::kFileExtension);
	if (!std::filesystem::exists(inPath)) throw std::runtime_error("input rawlog '" + inPath + "' does not exist");
	if (append && !std::filesystem::exists(appendArg.getValue()))
		throw std::runtime_error("--append: map '" + appendArg.getValue() + "' does not exist");
	if (linksArg.isSet() && !append) throw std::runtime_error("--links: only with --append");
	std::string cfgWhat;
	for (const auto& c : cfgArgs.getValue()) cfgWhat += (cfgWhat.empty() ? "" : " + ") + c;
	if (cfgWhat.empty()) cfgWhat = "(no config)";
	for (const auto& c : cfgArgs.getValue())
		if (!std::filesystem::exists(c)) throw std::runtime_error("config file '" + c + "' does not exist");
	mrpt::config::CConfigFileMemory cfgMem(core::layeredConfigText(cfgArgs.getValue()));
	try
	{
		if (append)
			localisation::checkLocaliseConfig(cfgMem, {}, cfgWhat);
		else
			vo::checkVOConfigSections(cfgMem);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(core::configError(cfgArgs.getValue(), cfgWhat, e.what()));
	}
	// No output is an input; the map is written to a temporary and renamed.
	io::OutputTransaction outputs;
	outputs.addInput(inPath, "input rawlog");
	outputs.addInput(io::imagesDirFor(inPath), "input rawlog's images folder");
	if (append) outputs.addInput(appendArg.getValue(), "--append map");
	if (gtArg.isSet()) outputs.addInput(gtArg.getValue(), "ground truth");
	for (const auto& c : cfgArgs.getValue()) outputs.addInput(c, "config");
	const std::string outTmp = outputs.addFile(outPath, "output map");
	const std::string linksTmp = linksArg.isSet() ? outputs.addFile(linksArg.getValue(), "--links") : "";
	CKeyframeMap::Ptr base;
	if (append)
	{
		base = CKeyframeMap::LoadFromFile(appendArg.getValue());
		base->reportLoadProblems(std::cerr, appendArg.getValue());
	}
	survey::TSurveyRunOptions so;
	so.configName = cfgWhat;
	if (gtArg.isSet())
	{
		so.gt = io::readTum(gtArg.getValue());
		so.gtName = gtArg.getValue();
	}
	mrpt::system::tokenize(chArg.getValue(), ", ", so.channels);
	so.sensorLabel = label.getValue();
	so.bridgeChannel = bridgeArg.getValue();
	if (runName.isSet()) so.runName = runName.getValue();
	const bool talk = !quiet.getValue();

	// ---- channels: the first one's VO makes the chain, every one is stored ------
	survey::SurveyRun surveyRun(inPath, cfgMem, so);
	for (const auto& w : surveyRun.warnings()) std::cerr << "warning: " << w << "\n";
	if (append)
		for (const auto& r : base->runs())
			if (r == surveyRun.runName())
				throw std::runtime_error(
					"--append: map '" + appendArg.getValue() + "' already holds a run named '" + r +
					"': name the new one with --run-name");
	surveyRun.setMinLoggingLevel(talk ? mrpt::system::LVL_WARN : mrpt::system::LVL_ERROR);
	if (talk) surveyRun.describe(std::cout);
	const auto t0 = std::chrono::steady_clock::now();
	CKeyframeMap::Ptr mapPtr = surveyRun.run([&](size_t nFrames, double progress) {
		if (!talk) return;
		if (nFrames == 1) std::cout << "calibration: " << surveyRun.stats().calib.asString() << "\n";
		if (nFrames % 100 == 0)
			std::cout << "frame " << nFrames << " (" << std::fixed << std::setprecision(0) << 100 * progress
					  << "%): " << surveyRun.map().keyframeCount() << " keyframes, " << std::setprecision(1)
					  << surveyRun.map().pathLength() << " m" << std::endl;
	});
	CKeyframeMap& kfmap = *mapPtr;
	const auto& st = surveyRun.stats();
	const size_t nFrames = st.frames;

	if (append)
	{
		// The run's map is complete: check it fits before localising.
		survey::checkAppendable(*base, kfmap, "map '" + appendArg.getValue() + "'", "run '" + inPath + "'");
		const auto rep = appendRun(cfgMem, cfgWhat, base, appendArg.getValue(), inPath, kfmap, surveyRun.runName(), label.getValue(), talk);
		if (!linksTmp.empty()) writeLinksCsv(linksTmp, rep);
		printAppendReport(rep, *base);
		mapPtr = base;
	}
	CKeyframeMap& outMap = *mapPtr;
	const auto tSave = std::chrono::steady_clock::now();
	outMap.saveToFile(outTmp);
	outputs.commit();
	const double msSave = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tSave).count();
	const double sWall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	std::cout << outMap.asString() << "\n"
			  << std::fixed << std::setprecision(2) << "frames: " << nFrames << ", VO breaks: " << st.breaks << " ("
			  << st.bridged << " bridged)"
			  << ", build " << st.msTotal / nFrames << " ms/frame (reading, filters, VO, every channel's features), save "
			  << msSave << " ms, wall " << sWall << " s; map -> " << outPath << "\n";
	if (!st.meanKeptReobservations.empty())
	{
		std::cout << "kept landmarks re-found, mean frames (window " << std::setprecision(1)
				  << kfmap.options.reobservation_window_m << " m):";
		for (size_t c = 0; c < st.meanKeptReobservations.size(); c++)
			std::cout << " " << kfmap.channels()[c].label << " " << st.meanKeptReobservations[c];
		std::cout << "\n";
	}
	if (kfmap.options.depth_from_reobservations && !st.refinedDepthShare.empty())
	{
		std::cout << "kept landmarks with a depth refined by their re-observations:";
		for (size_t c = 0; c < st.refinedDepthShare.size(); c++)
			std::cout << " " << kfmap.channels()[c].label << " " << std::setprecision(1) << 100 * st.refinedDepthShare[c] << " %";
		std::cout << "\n";
	}
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"survey", {"dual-channel keyframe map from a survey run (-i run.rawlog -o map.kfmap [-c ini] [--gt run.tum]); "
			   "--append MAP adds the run to MAP as a new experience",
			   run});
}  // namespace cmd_survey
