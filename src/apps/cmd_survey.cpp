/* shadyloc survey: a dual-channel keyframe map from a survey rawlog. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/io/Tum.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/survey/SurveyRun.h>
#include <shadyloc/vo/VOConfig.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/system/string_utils.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>

namespace
{
using namespace shadyloc;

bool endsWith(const std::string& s, const std::string& suf)
{
	return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
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
	TCLAP::ValueArg<std::string> cfgArg(
		"c", "config",
		"options .ini ([vo], [features], [features.<channel>], the channel sections [mono] [invariant], [map]; "
		"see config/vo.ini)",
		false, "", "vo.ini", cmd);
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
	if (!endsWith(outPath, CKeyframeMap::kFileExtension))
		throw std::runtime_error("output '" + outPath + "': map files end in " + CKeyframeMap::kFileExtension);
	if (!std::filesystem::exists(inPath)) throw std::runtime_error("input rawlog '" + inPath + "' does not exist");
	const auto cfg = vo::loadVOConfig(cfgArg.isSet() ? cfgArg.getValue() : "");
	survey::TSurveyRunOptions so;
	so.configName = cfgArg.isSet() ? cfgArg.getValue() : std::string("(no config)");
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
	survey::SurveyRun surveyRun(inPath, *cfg, so);
	for (const auto& w : surveyRun.warnings()) std::cerr << "warning: " << w << "\n";
	surveyRun.setMinLoggingLevel(talk ? mrpt::system::LVL_WARN : mrpt::system::LVL_ERROR);
	if (talk) surveyRun.describe(std::cout);
	const auto t0 = std::chrono::steady_clock::now();
	const CKeyframeMap::Ptr mapPtr = surveyRun.run([&](size_t nFrames, double progress) {
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

	const auto tSave = std::chrono::steady_clock::now();
	kfmap.saveToFile(outPath);
	const double msSave = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tSave).count();
	const double sWall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	std::cout << kfmap.asString() << "\n"
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
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"survey", {"dual-channel keyframe map from a survey run (-i run.rawlog -o map.kfmap [-c ini] [--gt run.tum])", run});
}  // namespace
