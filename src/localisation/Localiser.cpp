/* ShadyLoc — the public face (include/shadyloc/Localiser.h) over the
 * combined localisation system: options through the strict readers, the
 * live camera picked from a stream of observations and its frames paired by
 * the channels' frame assembler (colour, or a filtered rawlog's channels),
 * the system's per-frame record turned into a MOLA-shaped update. No
 * localisation logic here. */
#include <shadyloc/Localiser.h>
#include <shadyloc/core/Options.h>
#include <shadyloc/geometry/PoseCovariance.h>
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/io/StereoFrameSource.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/localisation/LocaliseRun.h>
#include <shadyloc/localisation/LocaliserAppKeys.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <functional>
#include <stdexcept>

namespace shadyloc
{
namespace
{
using localisation::LocalisationSystem;
using localisation::TLocalisationUpdate;

/** Every key of every section of `from` but `skip` into `to`, values as
 * written (inline comments too: the strict reader strips them on reading). */
void copySections(
	const mrpt::config::CConfigFileBase& from, mrpt::config::CConfigFileBase& to, const std::string& skip)
{
	std::vector<std::string> sections;
	from.getAllSections(sections);
	for (const auto& s : sections)
	{
		if (!skip.empty() && s == skip) continue;
		std::vector<std::string> keys;
		from.getAllKeys(s, keys);
		for (const auto& k : keys) to.write(s, k, from.read_string(s, k, ""));
	}
}

std::string nameOf(const mrpt::config::CConfigFileBase& cfg)
{
	const std::string s = core::settingsSource(cfg);
	return s.empty() ? "(in-memory config)" : s;
}

/** The share of the used fix's matches that its solve kept: a localiser's
 * accepted solve, or else the verified place the relocalisation took as
 * the fix. */
double inlierFraction(const TLocalisationUpdate& u)
{
	const auto* r = u.result(u.used);
	if (r && r->accepted()) return r->matches > 0 ? double(r->inliers) / r->matches : 0.0;
	return u.place.ok && u.place.matches > 0 ? double(u.place.inliers) / u.place.matches : 0.0;
}
}  // namespace

std::string toString(LocalisationStatus s)
{
	switch (s)
	{
		case LocalisationStatus::Localised: return "localised";
		case LocalisationStatus::DeadReckoning: return "dead_reckoning";
		case LocalisationStatus::NoPlace: return "no_place";
	}
	return "?";
}

// ---- options ------------------------------------------------------------------------------
void localisation::TLocaliserAppKeys::keys(core::KeyVisitor& v)
{
	using core::Range;
	v("sensor_label", sensor_label, "", Range::any(),
	  "the live camera (its colour label; its channels' observations are labelled `<sensor_label><suffix>`); "
	  "\"\" = the first colour stereo observation not labelled as one of the system's channels, or the camera of "
	  "the first channel observation");
	v("start_keyframe", start_keyframe, "", Range::atLeast(-1),
	  ">= 0: start near this map keyframe instead of by a search of the whole map (-1)");
}

void LocaliserOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
	source = nameOf(cfg);
	if (!section.empty() && cfg.sectionExists(section))
	{
		localisation::TLocaliserAppKeys app{sensor_label, start_keyframe};
		core::loadKeys(app, cfg, section);
	}
	mrpt::config::CConfigFileMemory sys;
	copySections(cfg, sys, section);
	localisation::checkLocaliseSections(sys, source);
	// Every struct read from the original, so that errors name its file.
	(void)LocalisationSystem::SetupFromConfig(cfg, {}, 0, source);
	sys.getContent(system_config);
}

void LocaliserOptions::saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const
{
	if (!section.empty())
	{
		// The keys only read through it.
		auto& self = const_cast<LocaliserOptions&>(*this);
		for (const auto& [key, text] : core::keyTexts(localisation::TLocaliserAppKeys{self.sensor_label, self.start_keyframe}))
			cfg.write(section, key, text);
	}
	copySections(mrpt::config::CConfigFileMemory(system_config), cfg, "");
}

// ---- the localiser ------------------------------------------------------------------------
struct Localiser::Impl
{
	CKeyframeMap::Ptr map;
	std::unique_ptr<LocalisationSystem> sys;
	std::string label;	//!< the live camera ("" until chosen)
	std::function<bool(const std::string&)> notDerived;	//!< false for a label with a channel's suffix (a filtered rawlog's)
	/** Pairs the live camera's observations into frames: its colour pair,
	 * or its channels' grey pairs (made when the first live one arrives). */
	std::unique_ptr<filters::ChannelFrameAssembler> frames;
	size_t offered = 0;	 //!< stereo observations offered (named in errors)
	std::optional<TLocalisationUpdate> last;

	Impl(CKeyframeMap::Ptr m, const LocaliserOptions& o) : map(std::move(m)), label(o.sensor_label)
	{
		if (map->isEmpty()) throw std::runtime_error("Localiser: the map has no keyframes: nothing to localise against");
		// The options may have been filled in code: checked as when loaded.
		const mrpt::config::CConfigFileMemory cfg(o.system_config);
		localisation::checkLocaliseSections(cfg, o.source);
		sys = LocalisationSystem::FromConfig(cfg, map, {}, 0, o.source);
		if (o.start_keyframe >= 0) sys->setStartKeyframe(static_cast<uint32_t>(o.start_keyframe));
		std::vector<std::string> suffixes;
		for (const auto& l : sys->channelLabels()) suffixes.push_back(sys->channelSetup(l).channel.suffix());
		notDerived = io::labelWithoutSuffixes(suffixes);
	}

	/** The camera whose channel `ch` an observation labelled `l` is, or "". */
	std::string cameraOfChannel(const std::string& l, const filters::TChannel& ch) const
	{
		const std::string& s = ch.suffix();
		if (s.empty() || l.size() <= s.size() || l.compare(l.size() - s.size(), s.size(), s) != 0) return "";
		const std::string cam = l.substr(0, l.size() - s.size());
		return label.empty() || cam == label ? cam : "";
	}

	/** The assembler for the camera `label`: colour (every channel made from
	 * it), or every channel's grey pair read from its own observations. */
	void assemble(bool read)
	{
		filters::TChannelPlan plan;
		plan.camera = label;
		for (const auto& l : sys->channelLabels())
		{
			plan.channels.push_back(sys->channelSetup(l).channel);
			filters::TChannelInput in;
			in.filtered = read;
			in.sensorLabel = read ? label + plan.channels.back().suffix() : label;
			plan.inputs.push_back(in);
		}
		frames = std::make_unique<filters::ChannelFrameAssembler>(plan, false);
	}

	/** At the first live observation: its camera's colour pair, or its
	 * channels' grey pairs when the observation is one of them. */
	bool choose(const mrpt::obs::CObservationStereoImages& obs)
	{
		std::string cam;
		for (const auto& l : sys->channelLabels())
			if (cam.empty()) cam = cameraOfChannel(obs.sensorLabel, sys->channelSetup(l).channel);
		if (cam.empty() && !(label.empty() ? notDerived(obs.sensorLabel) : obs.sensorLabel == label)) return false;
		label = cam.empty() ? obs.sensorLabel : cam;
		assemble(!cam.empty());
		return true;
	}

	/** The frame the observation completes, if any. */
	bool frameOf(const mrpt::obs::CObservationStereoImages::Ptr& obs, filters::TChannelFrame& f)
	{
		if (!frames && !choose(*obs)) return false;
		const bool colour = frames->plan().needsColour();
		// The colour pair wins while no frame is done: a filtered rawlog
		// holds both, and colour is what the channels are made from.
		if (!colour && frames->frames() == 0 && obs->sensorLabel == label) assemble(false);
		if (frames->plan().needsColour() && obs->sensorLabel == label && !obs->imageLeft.isColor())
			throw std::invalid_argument(
				"Localiser: '" + label + "' is a grey stereo pair; the localisers make their channels from colour images");
		const size_t k = offered++;
		return frames->add(obs, k, "Localiser: stereo observation #" + std::to_string(k), f);
	}

	LocalisationUpdate toUpdate(const TLocalisationUpdate& u, mrpt::Clock::time_point stamp) const
	{
		LocalisationUpdate r;
		r.timestamp = stamp;
		r.frames_since_fix = u.frames_since_fix;
		if (!u.placeKnown) return r;
		r.status = u.localised() ? LocalisationStatus::Localised : LocalisationStatus::DeadReckoning;
		if (u.localised())
		{
			r.method = u.used;
			r.quality = inlierFraction(u);
		}
		r.keyframe_id = u.kf_id;
		const uint32_t frame = map->frameOf(u.kf_id);
		if (frame != 0) r.reference_frame = "map/" + map->runs()[frame];
		r.pose_in_keyframe = u.pdf();
		// The keyframe's place in its frame: taken as exact.
		geometry::TPoseWithCov kf, rel;
		kf.T = map->keyframe(u.kf_id).T_map_kf;
		rel.T = u.T_kf_live;
		rel.cov = u.cov;
		r.pose = geometry::toCPose3DPDFGaussian(geometry::compose(kf, rel));
		return r;
	}
};

Localiser::Localiser(const std::string& mapFile, const LocaliserOptions& opts)
{
	CKeyframeMap::Ptr map;
	try
	{
		map = CKeyframeMap::LoadFromFile(mapFile);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("map '" + mapFile + "': " + e.what());
	}
	m_impl = std::make_unique<Impl>(std::move(map), opts);
}

Localiser::Localiser(mrpt::maps::CMetricMap::Ptr map, const LocaliserOptions& opts)
{
	auto kfmap = std::dynamic_pointer_cast<CKeyframeMap>(map);
	if (!kfmap)
		throw std::invalid_argument(
			std::string("Localiser: the map is ") + (map ? map->GetRuntimeClass()->className : "null") +
			", not a shadyloc keyframe map (CKeyframeMap)");
	m_impl = std::make_unique<Impl>(std::move(kfmap), opts);
}

Localiser::~Localiser() = default;
Localiser::Localiser(Localiser&&) noexcept = default;
Localiser& Localiser::operator=(Localiser&&) noexcept = default;

std::optional<LocalisationUpdate> Localiser::process(const mrpt::obs::CObservation::Ptr& obs)
{
	const auto stereo = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(obs);
	filters::TChannelFrame f;
	if (!stereo || !m_impl->frameOf(stereo, f)) return std::nullopt;
	// Channels made from colour on the system's threads, as processFrame does.
	const auto& frames = *m_impl->frames;
	const auto images = [&](size_t i, cv::Mat& l, cv::Mat& r) {
		frames.make(f, i);
		l = f.channels[i].left;
		r = f.channels[i].right;
	};
	m_impl->last = m_impl->sys->processChannels(images, f.calib, f.timestamp);
	return m_impl->toUpdate(*m_impl->last, stereo->timestamp);
}

const std::string& Localiser::sensorLabel() const { return m_impl->label; }

const mrpt::maps::CMetricMap& Localiser::map() const { return *m_impl->map; }

const localisation::TLocalisationUpdate& Localiser::lastDiagnostics() const
{
	if (!m_impl->last) throw std::logic_error("Localiser::lastDiagnostics: no frame processed yet");
	return *m_impl->last;
}

void Localiser::reset()
{
	m_impl->sys->reset();
	m_impl->last.reset();
	m_impl->frames.reset();  // a new run may come from another kind of input
}

}  // namespace shadyloc
