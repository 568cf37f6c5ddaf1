/* ShadyLoc — a survey rawlog into a keyframe map (docs/map.md). */
#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/features/SurfaceNormals.h>
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/survey/SurveyBuilder.h>
#include <shadyloc/survey/SurveyRun.h>
#include <shadyloc/vo/ChannelOptions.h>
#include <shadyloc/vo/StereoVO.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace shadyloc::survey
{
/** One channel of the survey: the filter that makes it and its feature
 * extractor (its frames come from the survey's one frame source). Not in an
 * anonymous namespace: SurveyRun::TImpl holds it. */
struct TSurveyChannel
{
	filters::TChannel channel;
	features::StereoFeatureExtractor extractor;
	map::TChannelParams params;	 //!< what the map records
};

struct SurveyRun::TImpl
{
	std::string inPath;
	TSurveyRunOptions opts;
	CKeyframeMap::Ptr map;
	std::vector<TSurveyChannel> channels;
	std::unique_ptr<filters::ChannelFrameSource> source;  //!< every channel's frames, paired
	vo::TStereoVOOptions voOptions;	 //!< of the chain's VO (its matcher re-finds landmarks)
	std::unique_ptr<vo::StereoVO> voChain;
	size_t bridgeIndex = 0;	 //!< the bridge VO's channel (0: none)
	std::unique_ptr<vo::StereoVO> voBridge;
	bool ran = false;
};

namespace
{
/** Run names end up in frames.csv (kf_run), file names and messages:
 * letters, digits, '_', '-' and '.' only, so that none needs quoting. */
/** The survey's features need grey images: a channel whose filter makes
 * colour ones (a linearised colour channel) cannot be stored. */
void checkGrey(const filters::TChannelFrame& fr)
{
	for (const auto& c : fr.channels)
		if (c.left.type() != CV_8UC1)
			throw std::runtime_error(
				fr.where + "channel '" + c.label + "': " + std::to_string(c.left.channels()) +
				"-channel images; the survey needs grey ones");
}

void checkRunName(const std::string& name, const std::string& what)
{
	const auto ok = [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-' || c == '.'; };
	if (name.empty() || !std::all_of(name.begin(), name.end(), ok))
		throw std::invalid_argument(
			what + ": a run name may hold only letters, digits, '_', '-' and '.' (it is written unquoted into "
			"frames.csv); give another with --run-name");
}

/** Index of the channel named by `name` (TSurveyRunOptions::bridgeChannel)
 * among the survey's; 0 for none. */
size_t bridgeChannelIndex(const std::vector<TSurveyChannel>& channels, const std::string& name)
{
	if (name == "none") return 0;
	if (name == "auto") return channels.size() > 1 ? 1 : 0;
	for (size_t i = 1; i < channels.size(); i++)
		if (channels[i].channel.label == name) return i;
	std::string have;
	for (size_t i = 1; i < channels.size(); i++) have += (have.empty() ? "" : ", ") + channels[i].channel.label;
	throw std::invalid_argument(
		"--bridge '" + name + "': not one of the stored channels after the chain's (" +
		(have.empty() ? std::string("none") : have) + "), nor 'auto' or 'none'");
}
}  // namespace

namespace
{
/** What the map records for a channel: the filter that made its images
 * (for a filtered rawlog the one its record names, not the config's) and
 * its features. Throws for derived images without a record. */
map::TChannelParams recordedParams(
	const mrpt::config::CConfigFileBase& cfg, const filters::TChannel& ch, const filters::TChannelInput& in,
	const std::string& inPath, const std::string& cfgName, std::vector<std::string>& warnings)
{
	const auto fo = vo::featureOptionsFor(cfg, ch.label);
	if (!in.filtered) return channelParams(ch.label, *ch.filter, fo);
	if (!in.recorded)
		throw std::runtime_error(
			inPath + ": holds " + ch.label + " images '" + in.sensorLabel + "' but no filter record" +
			(in.hasRecord ? " of suffix " + ch.suffix() : std::string()) +
			": how they were made is unknown, so the map could not be checked against live data (re-filter "
			"it with shadyloc filter, or survey the unfiltered run)");
	if (!in.recorded->sameImagesAs(*ch.filter))
		warnings.push_back(
			inPath + ": its " + ch.label + " images were made with " + in.recorded->describe() +
			" (filter record), not with " + cfgName + "'s [" + ch.label + "] " + ch.filter->describe() +
			"; the map records the filter that made them");
	return channelParams(ch.label, *in.recorded, fo);
}
}  // namespace

SurveyRun::SurveyRun(const std::string& inPath, const mrpt::config::CConfigFileBase& cfg, const TSurveyRunOptions& o)
	: mrpt::system::COutputLogger("SurveyRun"), m_impl(std::make_unique<TImpl>())
{
	auto& I = *m_impl;
	I.inPath = inPath;
	I.opts = o;
	if (!std::filesystem::exists(inPath)) throw std::runtime_error("input rawlog '" + inPath + "' does not exist");
	I.map = CKeyframeMap::Create();
	if (cfg.sectionExists("map")) I.map->options.loadFromConfigFile(cfg, "map");
	if (o.channels.empty()) throw std::invalid_argument("--channels: no channel named");
	const std::string& cfgName = o.configName;
	std::vector<filters::TChannel> chans;
	for (const auto& name : o.channels)
	{
		TSurveyChannel c{filters::channelFromConfig(cfg, name, cfgName), features::StereoFeatureExtractor(), {}};
		for (const auto& other : I.channels)
			if (other.channel.label == c.channel.label)
				throw std::invalid_argument("--channels: channel '" + c.channel.label + "' given twice");
		const auto fo = vo::featureOptionsFor(cfg, c.channel.label);
		c.extractor = features::StereoFeatureExtractor(fo);
		chans.push_back(c.channel);
		I.channels.push_back(std::move(c));
	}
	filters::TChannelFrameSourceOptions so;
	so.camera = o.sensorLabel;
	I.source = std::make_unique<filters::ChannelFrameSource>(inPath, chans, so);
	for (size_t i = 0; i < I.channels.size(); i++)
		I.channels[i].params = recordedParams(cfg, I.channels[i].channel, I.source->input(i), inPath, cfgName, m_warnings);
	I.voOptions = vo::voOptionsFor(cfg, I.channels[0].channel.label);
	I.voChain = std::make_unique<vo::StereoVO>(I.voOptions, I.channels[0].extractor.options());
	I.bridgeIndex = bridgeChannelIndex(I.channels, o.bridgeChannel);
	if (I.bridgeIndex > 0)
	{
		const auto& b = I.channels[I.bridgeIndex];
		I.voBridge = std::make_unique<vo::StereoVO>(vo::voOptionsFor(cfg, b.channel.label), b.extractor.options());
	}
	m_runName = o.runName.empty() ? std::filesystem::path(inPath).stem().string() : o.runName;
	checkRunName(m_runName, o.runName.empty() ? "run name '" + m_runName + "' (the stem of '" + inPath + "')"
											  : "--run-name '" + m_runName + "'");
}

SurveyRun::~SurveyRun() = default;

const CKeyframeMap& SurveyRun::map() const { return *m_impl->map; }

void SurveyRun::describe(std::ostream& out) const
{
	const auto& I = *m_impl;
	out << "survey of " << I.inPath << "\n";
	for (size_t i = 0; i < I.channels.size(); i++)
		out << "channel " << I.channels[i].params.asString() << "\n  " << I.source->describeInput(i) << "\n";
	out << "keyframe chain: the " << I.channels[0].channel.label << " VO"
		<< (I.voBridge ? ", its breaks bridged by the " + I.channels[I.bridgeIndex].channel.label + " VO" : std::string())
		<< "\n[map]\n";
	I.map->options.dumpToTextStream(out);
}

CKeyframeMap::Ptr SurveyRun::run(const std::function<void(size_t, double)>& onFrame)
{
	auto& I = *m_impl;
	if (I.ran) throw std::logic_error("SurveyRun::run: called twice");
	I.ran = true;
	CKeyframeMap& kfmap = *I.map;
	auto& channels = I.channels;
	auto& voChain = *I.voChain;
	voChain.setMinLoggingLevel(getMinLoggingLevel());
	const std::string& inPath = I.inPath;
	std::unique_ptr<SurveyBuilder> builder;
	size_t& nFrames = m_stats.frames;
	std::optional<vo::TChainReference> bridgeAtLast;  // the last map keyframe as the bridge VO saw it

	// One frame source pairs the channels' images (read or made) per frame.
	filters::TChannelFrame fr;
	for (;;)
	{
		const auto tf = std::chrono::steady_clock::now();	// reading and filters count too
		if (!I.source->next(fr)) break;
		checkGrey(fr);
		const auto& f0 = fr.channels[0];
		if (nFrames == 0)
		{
			m_stats.calib = fr.calib;
			std::vector<map::TChannelParams> params;
			for (const auto& c : channels) params.push_back(c.params);
			kfmap.setup(m_stats.calib, fr.size.width, fr.size.height, params);
			builder = std::make_unique<SurveyBuilder>(kfmap, m_runName, I.voOptions);
		}
		const auto& calib = m_stats.calib;
		const double t = fr.timestamp;
		const size_t before = voChain.keyframes().size();
		// Selecting landmarks by re-observation needs every channel's
		// measurements of every frame; otherwise only at map keyframes.
		const bool everyFrame = builder->needsFrames();
		std::vector<features::TStereoFrame> frames(everyFrame ? channels.size() : 0);
		for (size_t c = 0; c < frames.size(); c++)
			channels[c].extractor.process(fr.channels[c].left, fr.channels[c].right, calib, frames[c]);
		vo::TFrameResult res;
		if (everyFrame)
		{
			voChain.track(frames[0], calib, t);
			res = voChain.commit();
		}
		else
			res = voChain.process(f0.left, f0.right, calib, t);
		// The bridge VO on its own channel: where the chain's VO breaks and
		// it does not, its motion links the segment on (SurveyBuilder::bridge).
		std::optional<vo::TChainReference> bridgeNow;
		if (I.voBridge)
		{
			auto& vb = *I.voBridge;
			const size_t bBefore = vb.keyframes().size();
			vo::TFrameResult bres;
			if (everyFrame)
			{
				vb.track(frames[I.bridgeIndex], calib, t);
				bres = vb.commit();
			}
			else
				bres = vb.process(fr.channels[I.bridgeIndex].left, fr.channels[I.bridgeIndex].right, calib, t);
			bridgeNow = vo::chainReference(bres, vb.keyframes(), bBefore);
		}
		if (builder->offer(res, voChain.keyframes(), before))
		{
			if (builder->bridgeable() && bridgeAtLast && bridgeNow)
			{
				const auto link = vo::poseAlongChain(
					I.voBridge->keyframes(), bridgeAtLast->ref, bridgeAtLast->T_ref_f, bridgeNow->ref, bridgeNow->T_ref_f);
				if (link) builder->bridge(*link);
			}
			bridgeAtLast = bridgeNow;  // the map keyframe to come, as the bridge VO saw it
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
				features::TStereoFrame one;
				channels[c].extractor.process(fr.channels[c].left, fr.channels[c].right, calib, one);
				meas[c] = std::move(one.meas);
			}
			if (kfmap.options.surface_normals)
			{
				// One dense disparity image, from the chain's channel: the
				// geometry it measures is every channel's.
				features::TSurfaceNormalOptions no;
				no.window_radius_px = kfmap.options.normal_window_px;
				const cv::Mat disp = features::denseDisparity(f0.left, f0.right, no);
				for (auto& m : meas) features::estimateNormals(disp, calib, no, m);
			}
			std::optional<Eigen::Isometry3d> T_gt;
			if (I.opts.gt)
			{
				const io::Trajectory one{{t, Eigen::Isometry3d::Identity()}};
				const auto pairs = io::associate(*I.opts.gt, one, 0.01);
				if (!pairs.empty())
				{
					T_gt = (*I.opts.gt)[pairs[0].first].T;
					m_stats.gtKeyframes++;
				}
			}
			if (everyFrame) builder->addFrame(std::move(frames));
			builder->addKeyframe(meas, T_gt);
		}
		else if (everyFrame)
			builder->addFrame(std::move(frames));
		nFrames++;
		m_stats.msTotal += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tf).count();
		if (onFrame) onFrame(nFrames, I.source->progress());
	}
	if (nFrames == 0) throw std::runtime_error(I.source->noFramesMessage());
	builder->finish();
	m_stats.meanKeptReobservations = builder->meanKeptReobservations();
	m_stats.refinedDepthShare = builder->refinedDepthShare();
	if (kfmap.isEmpty()) throw std::runtime_error(inPath + ": the VO never tracked: no keyframes, no map written");
	if (I.opts.gt && m_stats.gtKeyframes == 0)
		throw std::runtime_error(
			I.opts.gtName + ": no ground-truth pose within 10 ms of any keyframe of " + inPath);
	m_stats.breaks = builder->breaks();
	m_stats.bridged = builder->bridged();
	return I.map;
}

}  // namespace shadyloc::survey
