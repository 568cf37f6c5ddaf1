/* shadyloc survey: a dual-channel keyframe map from a survey rawlog. */
#include "Command.h"

#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/map/SurveyBuilder.h>
#include <shadyloc/vo/Channel.h>
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>

namespace
{
using namespace shadyloc;
using Stereo = mrpt::obs::CObservationStereoImages;

bool endsWith(const std::string& s, const std::string& suf)
{
	return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

/** The invariant parameters recorded by `shadyloc filter` in a filtered rawlog. */
std::optional<image::InvariantParams> recordedInvariantParams(const std::string& path)
{
	const std::string rec = filters::readPipelineRecord(path);
	if (rec.empty()) return std::nullopt;
	mrpt::config::CConfigFileMemory cfg(rec);
	const auto pipeline = filters::FilterPipeline::FromConfig(cfg, path + " (filter record)");
	for (const auto& f : pipeline.filters)
		if (const auto inv = std::dynamic_pointer_cast<CFilterInvariant>(f)) return inv->params();
	return std::nullopt;
}

/** One channel of the survey: how its grey pair is made, and its extractor. */
struct TChannel
{
	vo::ChannelConverter conv;
	features::StereoFeatureExtractor extractor;
	std::string filteredLabel;	//!< "<base>_mono" / "<base>_inv" when the rawlog holds it
	map::TChannelParams params;
};

/** A frame: observations of one timestamp (the colour pair and/or filtered ones). */
struct TFrame
{
	mrpt::Clock::time_point t{};
	std::shared_ptr<Stereo> colour;
	std::map<std::string, std::shared_ptr<Stereo>> filtered;
	std::string where;
	bool empty() const { return !colour && filtered.empty(); }
};

int run(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
		"Builds a dual-channel keyframe map (" + std::string(CKeyframeMap::kFileExtension) +
			") from a survey rawlog: the monochrome VO chooses the keyframes, and at each one the stereo "
			"measurements of both channels (mono, invariant) are stored. Uses the <label>_mono / <label>_inv "
			"observations of a filtered rawlog when present, otherwise converts the colour images.",
		' ', "0.1");
	TCLAP::ValueArg<std::string> in("i", "input", "survey rawlog", true, "", "run.rawlog", cmd);
	TCLAP::ValueArg<std::string> out(
		"o", "output", std::string("map file (") + CKeyframeMap::kFileExtension + ")", true, "", "map.kfmap", cmd);
	TCLAP::ValueArg<std::string> cfgArg(
		"c", "config", "options .ini ([vo], [features], [features.invariant], [invariant], [map])", false, "",
		"vo.ini", cmd);
	TCLAP::ValueArg<std::string> gtArg("", "gt", "ground truth (TUM), stored beside the keyframes", false, "", "run.tum", cmd);
	TCLAP::ValueArg<std::string> runName("", "run-name", "survey run name (default: the rawlog's stem)", false, "", "name", cmd);
	TCLAP::ValueArg<std::string> label("", "label", "sensor label of the colour stereo camera", false, "", "label", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "no option dump or progress", cmd);
	cmd.parse(argc, argv);

	const std::string inPath = in.getValue(), outPath = out.getValue();
	if (!endsWith(outPath, CKeyframeMap::kFileExtension))
		throw std::runtime_error("output '" + outPath + "': map files end in " + CKeyframeMap::kFileExtension);
	if (!std::filesystem::exists(inPath)) throw std::runtime_error("input rawlog '" + inPath + "' does not exist");
	std::unique_ptr<mrpt::config::CConfigFileBase> cfg;
	if (cfgArg.isSet())
	{
		if (!std::filesystem::exists(cfgArg.getValue()))
			throw std::runtime_error("config file '" + cfgArg.getValue() + "' does not exist");
		cfg = std::make_unique<mrpt::config::CConfigFile>(cfgArg.getValue());
	}
	else
		cfg = std::make_unique<mrpt::config::CConfigFileMemory>("");
	std::optional<eval::Trajectory> gt;
	if (gtArg.isSet()) gt = eval::readTum(gtArg.getValue());

	auto mapPtr = CKeyframeMap::Create();
	CKeyframeMap& kfmap = *mapPtr;
	if (cfg->sectionExists("map")) kfmap.options.loadFromConfigFile(*cfg, "map");
	const bool talk = !quiet.getValue();

	// ---- channels: the mono VO's chain, both channels' measurements ------------
	std::vector<TChannel> channels;
	for (const auto c : {vo::Channel::Mono, vo::Channel::Invariant})
	{
		const auto conv = vo::ChannelConverter::FromConfig(*cfg, vo::toString(c));
		const auto fo = vo::featureOptionsFor(*cfg, c);
		channels.push_back({conv, features::StereoFeatureExtractor(fo), "", {}});
	}
	// Which streams the rawlog holds: the colour pair and any filtered channels.
	std::string base = label.getValue();
	{
		io::RawlogReader rd(inPath);
		for (int i = 0; i < 400; i++)
		{
			const auto obj = rd.next();
			if (!obj) break;
			for (const auto& o : io::observationsIn(obj))
			{
				if (!IS_CLASS(*o, Stereo)) continue;
				const auto& l = o->sensorLabel;
				for (auto& ch : channels)
				{
					const std::string suf = vo::channelSuffix(ch.conv.channel());
					if (endsWith(l, suf) && (base.empty() || l == base + suf)) ch.filteredLabel = l;
				}
				if (base.empty() && !endsWith(l, "_mono") && !endsWith(l, "_inv") && !endsWith(l, "_lin")) base = l;
			}
		}
	}
	for (auto& ch : channels)
	{
		image::InvariantParams inv = ch.conv.invariantParams();
		if (ch.conv.channel() == vo::Channel::Invariant && !ch.filteredLabel.empty())
		{
			// The map records what made the images: the filter record, not the config.
			const auto rec = recordedInvariantParams(inPath);
			if (!rec)
				throw std::runtime_error(
					inPath + ": holds invariant images '" + ch.filteredLabel +
					"' but no filter record: their transform is unknown, so the map could not be checked against "
					"live data (re-filter it with shadyloc filter, or survey the unfiltered run)");
			inv = *rec;
		}
		const bool mono = ch.conv.channel() == vo::Channel::Mono;
		ch.params = map::TChannelParams::From(
			vo::toString(ch.conv.channel()), mono ? map::ChannelKind::Mono : map::ChannelKind::Invariant,
			ch.extractor.options(), inv, image::ChannelOrder::BGR);
	}
	const vo::TStereoVOOptions vopt = vo::voOptionsFor(*cfg, vo::Channel::Mono);
	vo::StereoVO voChain(vopt, channels[0].extractor.options());
	voChain.setMinLoggingLevel(talk ? mrpt::system::LVL_WARN : mrpt::system::LVL_ERROR);
	if (talk)
	{
		std::cout << "survey of " << inPath << "\n";
		for (const auto& ch : channels)
			std::cout << "channel " << ch.params.asString() << ": "
					  << (ch.filteredLabel.empty() ? "converted from '" + base + "'" : "filtered '" + ch.filteredLabel + "'")
					  << "\n";
		std::cout << "[map]\n";
		kfmap.options.dumpToTextStream(std::cout);
	}

	const std::string run = runName.isSet() ? runName.getValue() : std::filesystem::path(inPath).stem().string();
	std::unique_ptr<map::CSurveyBuilder> builder;
	io::RawlogReader rd(inPath);
	geometry::TStereoCalib calib;
	cv::Size size;
	size_t nFrames = 0, nGt = 0;
	double msTotal = 0;
	const auto t0 = std::chrono::steady_clock::now();

	auto process = [&](TFrame& f) {
		const auto tf = std::chrono::steady_clock::now();
		// Grey pairs per channel: the filtered observation, or converted colour.
		std::vector<std::pair<cv::Mat, cv::Mat>> grey(channels.size());
		std::shared_ptr<Stereo> any = f.colour;
		for (size_t c = 0; c < channels.size(); c++)
		{
			auto& ch = channels[c];
			const auto it = ch.filteredLabel.empty() ? f.filtered.end() : f.filtered.find(ch.filteredLabel);
			if (it != f.filtered.end())
			{
				io::loadExternalImages(*it->second);
				grey[c] = {it->second->imageLeft.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY),
						   it->second->imageRight.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY)};
				if (!any) any = it->second;
			}
			else
			{
				if (!f.colour)
					throw std::runtime_error(
						f.where + ": no '" + (ch.filteredLabel.empty() ? base : ch.filteredLabel) + "' stereo pair for channel '" +
						ch.params.label + "'");
				io::loadExternalImages(*f.colour);
				try
				{
					ch.conv.convert(f.colour->imageLeft.asCvMatRef(), grey[c].first);
					ch.conv.convert(f.colour->imageRight.asCvMatRef(), grey[c].second);
				}
				catch (const std::exception& e)
				{
					throw std::runtime_error(f.where + ": channel '" + ch.params.label + "': " + e.what());
				}
			}
			if (grey[c].first.empty() || grey[c].first.size() != grey[c].second.size() || grey[c].first.type() != CV_8UC1)
				throw std::runtime_error(f.where + ": channel '" + ch.params.label + "': empty, mismatched or non-grey images");
		}
		if (nFrames == 0)
		{
			calib = geometry::TStereoCalib::FromObservation(*any);
			size = grey[0].first.size();
			kfmap.setup(calib, size.width, size.height, {channels[0].params, channels[1].params});
			builder = std::make_unique<map::CSurveyBuilder>(kfmap, run);
			if (talk) std::cout << "calibration: " << calib.asString() << "\n";
		}
		else if (grey[0].first.size() != size)
			throw std::runtime_error(f.where + ": image size changed within the run");
		for (const auto& g : grey)
			if (g.first.size() != size) throw std::runtime_error(f.where + ": channels of different image sizes");
		const double t = mrpt::Clock::toDouble(f.t);
		const size_t before = voChain.keyframes().size();
		const auto res = voChain.process(grey[0].first, grey[0].second, calib, t);
		if (builder->offer(res, voChain.keyframes(), before))
		{
			std::vector<std::vector<features::TStereoMeasurement>> meas(channels.size());
			for (size_t c = 0; c < channels.size(); c++)
			{
				if (c == 0 && res.keyframe)
				{
					meas[c] = voChain.keyframes().back().meas;	// the VO just extracted them
					continue;
				}
				features::TStereoFrame fr;
				channels[c].extractor.process(grey[c].first, grey[c].second, calib, fr);
				meas[c] = std::move(fr.meas);
			}
			std::optional<Eigen::Isometry3d> T_gt;
			if (gt)
			{
				eval::Trajectory one{{t, Eigen::Isometry3d::Identity()}};
				const auto pairs = eval::associate(*gt, one, 0.01);
				if (!pairs.empty())
				{
					T_gt = (*gt)[pairs[0].first].T;
					nGt++;
				}
			}
			builder->addKeyframe(meas, T_gt);
		}
		nFrames++;
		msTotal += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tf).count();
		if (talk && nFrames % 100 == 0)
			std::cout << "frame " << nFrames << " (" << std::fixed << std::setprecision(0) << 100 * rd.progress()
					  << "%): " << kfmap.keyframeCount() << " keyframes, " << std::setprecision(1) << kfmap.pathLength()
					  << " m" << std::endl;
	};

	TFrame cur;
	while (const auto obj = rd.next())
	{
		for (const auto& o : io::observationsIn(obj))
		{
			auto st = std::dynamic_pointer_cast<Stereo>(o);
			if (!st) continue;
			const bool isColour = st->sensorLabel == base;
			bool isFiltered = false;
			for (const auto& ch : channels) isFiltered |= !ch.filteredLabel.empty() && st->sensorLabel == ch.filteredLabel;
			if (!isColour && !isFiltered) continue;
			if (!cur.empty() && st->timestamp != cur.t)
			{
				process(cur);
				cur = TFrame();
			}
			cur.t = st->timestamp;
			cur.where = rd.where("stereo observation '" + st->sensorLabel + "'");
			if (isColour)
				cur.colour = st;
			else
				cur.filtered[st->sensorLabel] = st;
		}
	}
	if (!cur.empty()) process(cur);
	if (nFrames == 0)
		throw std::runtime_error(inPath + ": no stereo observations" + (base.empty() ? "" : " labelled '" + base + "'"));
	if (kfmap.isEmpty()) throw std::runtime_error(inPath + ": the VO never tracked: no keyframes, no map written");
	if (gt && nGt == 0)
		throw std::runtime_error(gtArg.getValue() + ": no ground-truth pose within 10 ms of any keyframe of " + inPath);

	const auto tSave = std::chrono::steady_clock::now();
	kfmap.saveToFile(outPath);
	const double msSave = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tSave).count();
	const double sWall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	std::cout << kfmap.asString() << "\n"
			  << std::fixed << std::setprecision(2) << "frames: " << nFrames << ", VO breaks: " << builder->breaks()
			  << ", build " << msTotal / nFrames << " ms/frame (VO + both channels' features), save " << msSave
			  << " ms, wall " << sWall << " s; map -> " << outPath << "\n";
	return 0;
}
shadyloc::apps::RegisterCommand reg(
	"survey", {"dual-channel keyframe map from a survey run (-i run.rawlog -o map.kfmap [-c ini] [--gt run.tum])", run});
}  // namespace
