/* shadyloc survey: a dual-channel keyframe map from a survey rawlog. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/io/StereoFrameSource.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/survey/SurveyBuilder.h>
#include <shadyloc/vo/ChannelOptions.h>
#include <shadyloc/vo/StereoVO.h>
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

/** One channel of the survey: the filter that makes it, where its frames
 * come from, and its feature extractor. */
struct TSurveyChannel
{
	filters::TChannel channel;
	filters::TChannelInput input;
	features::StereoFeatureExtractor extractor;
	map::TChannelParams params;	 //!< what the map records
	std::unique_ptr<io::StereoFrameSource> source;
	io::TStereoFrame frame;	 //!< the current frame
};

bool sameCalib(const geometry::TStereoCalib& a, const geometry::TStereoCalib& b)
{
	const auto eq = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x)); };
	return eq(a.fx, b.fx) && eq(a.fy, b.fy) && eq(a.cx, b.cx) && eq(a.cy, b.cy) && eq(a.cxR, b.cxR) &&
		   eq(a.baseline, b.baseline);
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
	TCLAP::ValueArg<std::string> gtArg("", "gt", "ground truth (TUM), stored beside the keyframes", false, "", "run.tum", cmd);
	TCLAP::ValueArg<std::string> runName("", "run-name", "survey run name (default: the rawlog's stem)", false, "", "name", cmd);
	TCLAP::ValueArg<std::string> label(
		"", "label", "sensor label of the colour stereo camera (default: the first one found)", false, "", "label", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no option dump or progress", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;

	const std::string inPath = in.getValue(), outPath = out.getValue();
	if (!endsWith(outPath, CKeyframeMap::kFileExtension))
		throw std::runtime_error("output '" + outPath + "': map files end in " + CKeyframeMap::kFileExtension);
	if (!std::filesystem::exists(inPath)) throw std::runtime_error("input rawlog '" + inPath + "' does not exist");
	const auto cfg = vo::loadVOConfig(cfgArg.isSet() ? cfgArg.getValue() : "");
	const std::string cfgName = cfgArg.isSet() ? cfgArg.getValue() : std::string("(no config)");
	std::optional<io::Trajectory> gt;
	if (gtArg.isSet()) gt = io::readTum(gtArg.getValue());

	auto mapPtr = CKeyframeMap::Create();
	CKeyframeMap& kfmap = *mapPtr;
	if (cfg->sectionExists("map")) kfmap.options.loadFromConfigFile(*cfg, "map");
	const bool talk = !quiet.getValue();

	// ---- channels: the first one's VO makes the chain, every one is stored ------
	std::vector<std::string> names;
	mrpt::system::tokenize(chArg.getValue(), ", ", names);
	if (names.empty()) throw std::invalid_argument("--channels: no channel named");
	std::vector<TSurveyChannel> channels;
	for (const auto& name : names)
	{
		TSurveyChannel c{
			filters::channelFromConfig(*cfg, name, cfgName), {}, features::StereoFeatureExtractor(), {}, {}, {}};
		for (const auto& o : channels)
			if (o.channel.label == c.channel.label)
				throw std::invalid_argument("--channels: channel '" + c.channel.label + "' given twice");
		c.input = filters::resolveChannelInput(inPath, c.channel, label.getValue());
		const auto fo = vo::featureOptionsFor(*cfg, c.channel.label);
		c.extractor = features::StereoFeatureExtractor(fo);
		// The map records what made the images: for a filtered rawlog the
		// filter its record names, not the config's.
		const CObservationFilter* madeBy = c.channel.filter.get();
		if (c.input.filtered)
		{
			if (!c.input.recorded)
				throw std::runtime_error(
					inPath + ": holds " + c.channel.label + " images '" + c.input.sensorLabel + "' but no filter record" +
					(c.input.hasRecord ? " of suffix " + c.channel.suffix() : std::string()) +
					": how they were made is unknown, so the map could not be checked against live data (re-filter "
					"it with shadyloc filter, or survey the unfiltered run)");
			madeBy = c.input.recorded.get();
			if (!c.input.recorded->sameImagesAs(*c.channel.filter))
				std::cerr << "warning: " << inPath << ": its " << c.channel.label << " images were made with "
						  << c.input.recorded->describe() << " (filter record), not with " << cfgName << "'s ["
						  << c.channel.label << "] " << c.channel.filter->describe()
						  << "; the map records the filter that made them\n";
		}
		c.params = survey::channelParams(c.channel.label, *madeBy, fo);
		c.source = std::make_unique<io::StereoFrameSource>(inPath, c.input.sourceOptions);
		channels.push_back(std::move(c));
	}
	const vo::TStereoVOOptions vopt = vo::voOptionsFor(*cfg, channels[0].channel.label);
	vo::StereoVO voChain(vopt, channels[0].extractor.options());
	voChain.setMinLoggingLevel(talk ? mrpt::system::LVL_WARN : mrpt::system::LVL_ERROR);
	if (talk)
	{
		std::cout << "survey of " << inPath << "\n";
		for (const auto& c : channels)
			std::cout << "channel " << c.params.asString() << "\n  "
					  << (c.input.filtered ? "from the filtered observations '" + c.input.sensorLabel + "'"
										   : "filtered on the fly from the colour camera" +
												 (c.input.sensorLabel.empty() ? std::string() : " '" + c.input.sensorLabel + "'"))
					  << "\n";
		std::cout << "keyframe chain: the " << channels[0].channel.label << " VO\n[map]\n";
		kfmap.options.dumpToTextStream(std::cout);
	}

	const std::string run = runName.isSet() ? runName.getValue() : std::filesystem::path(inPath).stem().string();
	std::unique_ptr<survey::CSurveyBuilder> builder;
	geometry::TStereoCalib calib;
	size_t nFrames = 0, nGt = 0;
	double msTotal = 0;
	const auto t0 = std::chrono::steady_clock::now();

	// The channels' sources walk the rawlog in lockstep: the same frame index
	// and timestamp from each, or the run is refused.
	for (;;)
	{
		const auto tf = std::chrono::steady_clock::now();
		size_t have = 0;
		for (auto& c : channels) have += c.source->next(c.frame) ? 1 : 0;
		if (have == 0) break;
		const auto& f0 = channels[0].frame;
		const std::string where0 = "'" + inPath + "': frame " + std::to_string(nFrames);
		if (have != channels.size())
		{
			std::string ended;
			for (const auto& c : channels)
				if (c.source->frames() == nFrames) ended += (ended.empty() ? "" : ", ") + c.channel.label;
			throw std::runtime_error(
				where0 + ": the frames of channel(s) " + ended +
				" end here while the other channels have more (a partly filtered rawlog?)");
		}
		for (const auto& c : channels)
		{
			const auto& f = c.frame;
			const std::string where = c.source->reader().where(
				"frame " + std::to_string(f.index) + " (sensor '" + f.sensorLabel + "', channel '" + c.channel.label + "')");
			if (f.index != f0.index || f.timestamp != f0.timestamp)
				throw std::runtime_error(
					where + ": timestamp " + std::to_string(f.timestamp) + " is not channel '" +
					channels[0].channel.label + "''s frame " + std::to_string(f0.index) + " at " +
					std::to_string(f0.timestamp) + " (the channels' frames must pair up)");
			if (f.left.type() != CV_8UC1)
				throw std::runtime_error(
					where + ": " + std::to_string(f.left.channels()) + "-channel images; the survey needs grey ones");
			if (!sameCalib(f.calib, f0.calib) || f.left.size() != f0.left.size())
				throw std::runtime_error(where + ": calibration or image size differs from channel '" +
										 channels[0].channel.label + "''s");
		}
		if (nFrames == 0)
		{
			calib = f0.calib;
			std::vector<map::TChannelParams> params;
			for (const auto& c : channels) params.push_back(c.params);
			kfmap.setup(calib, f0.left.cols, f0.left.rows, params);
			builder = std::make_unique<survey::CSurveyBuilder>(kfmap, run, vopt);
			if (talk) std::cout << "calibration: " << calib.asString() << "\n";
		}
		const double t = f0.timestamp;
		const size_t before = voChain.keyframes().size();
		// Selecting landmarks by re-observation needs every channel's
		// measurements of every frame; otherwise only at map keyframes.
		const bool everyFrame = builder->needsFrames();
		std::vector<features::TStereoFrame> frames(everyFrame ? channels.size() : 0);
		for (size_t c = 0; c < frames.size(); c++)
			channels[c].extractor.process(channels[c].frame.left, channels[c].frame.right, calib, frames[c]);
		vo::TFrameResult res;
		if (everyFrame)
		{
			voChain.track(frames[0], calib, t);
			res = voChain.commit();
		}
		else
			res = voChain.process(f0.left, f0.right, calib, t);
		const bool isKeyframe = builder->offer(res, voChain.keyframes(), before);
		if (isKeyframe)
		{
			std::vector<std::vector<features::TStereoMeasurement>> meas(channels.size());
			for (size_t c = 0; c < channels.size(); c++)
			{
				if (everyFrame)
				{
					meas[c] = frames[c].meas;
					continue;
				}
				if (c == 0 && res.keyframe)
				{
					meas[c] = voChain.keyframes().back().meas;	// the VO just extracted them
					continue;
				}
				features::TStereoFrame fr;
				channels[c].extractor.process(channels[c].frame.left, channels[c].frame.right, calib, fr);
				meas[c] = std::move(fr.meas);
			}
			std::optional<Eigen::Isometry3d> T_gt;
			if (gt)
			{
				const io::Trajectory one{{t, Eigen::Isometry3d::Identity()}};
				const auto pairs = eval::associate(*gt, one, 0.01);
				if (!pairs.empty())
				{
					T_gt = (*gt)[pairs[0].first].T;
					nGt++;
				}
			}
			if (everyFrame) builder->addFrame(std::move(frames));
			builder->addKeyframe(meas, T_gt);
		}
		else if (everyFrame)
			builder->addFrame(std::move(frames));
		nFrames++;
		msTotal += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tf).count();
		if (talk && nFrames % 100 == 0)
			std::cout << "frame " << nFrames << " (" << std::fixed << std::setprecision(0)
					  << 100 * channels[0].source->progress() << "%): " << kfmap.keyframeCount() << " keyframes, "
					  << std::setprecision(1) << kfmap.pathLength() << " m" << std::endl;
	}
	if (nFrames == 0) throw std::runtime_error(channels[0].source->noFramesMessage());
	builder->finish();
	if (kfmap.isEmpty()) throw std::runtime_error(inPath + ": the VO never tracked: no keyframes, no map written");
	if (gt && nGt == 0)
		throw std::runtime_error(gtArg.getValue() + ": no ground-truth pose within 10 ms of any keyframe of " + inPath);

	const auto tSave = std::chrono::steady_clock::now();
	kfmap.saveToFile(outPath);
	const double msSave = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tSave).count();
	const double sWall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	std::cout << kfmap.asString() << "\n"
			  << std::fixed << std::setprecision(2) << "frames: " << nFrames << ", VO breaks: " << builder->breaks()
			  << ", build " << msTotal / nFrames << " ms/frame (reading, filters, VO, every channel's features), save "
			  << msSave << " ms, wall " << sWall << " s; map -> " << outPath << "\n";
	const auto reobs = builder->meanKeptReobservations();
	if (!reobs.empty())
	{
		std::cout << "kept landmarks re-found, mean frames (window " << std::setprecision(1)
				  << kfmap.options.reobservation_window_m << " m):";
		for (size_t c = 0; c < reobs.size(); c++) std::cout << " " << channels[c].channel.label << " " << reobs[c];
		std::cout << "\n";
	}
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"survey", {"dual-channel keyframe map from a survey run (-i run.rawlog -o map.kfmap [-c ini] [--gt run.tum])", run});
}  // namespace
