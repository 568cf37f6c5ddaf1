/* ShadyLoc — one localisation run (docs/localisation.md); its output files
 * are the evaluation's (eval/LocaliseOutputs.h). */
#include <shadyloc/core/Settings.h>
#include <shadyloc/localisation/LocaliseRun.h>
#include <shadyloc/localisation/Oracle.h>
#include <shadyloc/vo/VOConfig.h>

#include <algorithm>
#include <stdexcept>

namespace shadyloc::localisation
{

// ---------------------------------------------------------------------------
void checkLocaliseSections(const mrpt::config::CConfigFileBase& cfg, const std::string& what)
{
	std::vector<std::string> known = vo::voConfigSections();
	for (const char* s : {"mono", "invariant", "map", "filters", "localise", "localiser", "localiser.mono", "localiser.invariant"})
		known.push_back(s);
	std::vector<std::string> sections;
	cfg.getAllSections(sections);
	for (const auto& s : sections)
		if (s.rfind("localiser.", 0) == 0 || s.rfind("vo.", 0) == 0 || s.rfind("features.", 0) == 0 ||
			cfg.keyExists(s, "class"))	// per-channel overrides; a channel's filter section
			known.push_back(s);
	core::checkSections(cfg, known, "localise config " + what);
}

void checkLocaliseConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::vector<std::string>& localisers, const std::string& what)
{
	checkLocaliseSections(cfg, what);
	(void)LocalisationSystem::SetupFromConfig(cfg, localisers, 0, what);
}

LocaliseRun::LocaliseRun(
	const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::string& mapPath,
	const std::string& livePath, const TLocaliseRunOptions& o)
	: m_livePath(livePath)
{
	makeSystem(cfg, std::move(map), mapPath, o);
	openLive(o.sensorLabel, nullptr);
}

LocaliseRun::LocaliseRun(
	const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::string& mapPath,
	filters::TObjectFeed feed, const TLocaliseRunOptions& o)
	: m_livePath(feed.name)
{
	makeSystem(cfg, std::move(map), mapPath, o);
	openLive(o.sensorLabel, &feed);
}

void LocaliseRun::makeSystem(
	const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::string& mapPath,
	const TLocaliseRunOptions& o)
{
	if (map->isEmpty()) throw std::runtime_error("map '" + mapPath + "' has no keyframes: nothing to localise against");
	const size_t nKf = map->keyframeCount();
	// frames.csv writes run names unquoted (kf_run): maps surveyed before
	// names were restricted may hold one that would split its row.
	for (const auto& run : map->runs())
		if (run.find_first_of(",\"\r\n") != std::string::npos)
			throw std::runtime_error(
				"map '" + mapPath + "': run name '" + run +
				"' holds a comma, quote or line break, which frames.csv cannot hold: survey it again with --run-name");
	try
	{
		checkLocaliseSections(cfg, o.configWhat);
		m_sys = LocalisationSystem::FromConfig(cfg, std::move(map), o.localisers, o.threads, o.configWhat);
	}
	catch (const std::out_of_range& e)
	{
		throw std::runtime_error("map '" + mapPath + "': " + e.what());
	}
	catch (const std::runtime_error& e)
	{
		throw std::runtime_error("map '" + mapPath + "' and config " + o.configWhat + ": " + e.what());
	}
	if (o.startKf >= 0)
	{
		if (static_cast<size_t>(o.startKf) >= nKf)
			throw std::runtime_error(
				"--start-kf " + std::to_string(o.startKf) + ": the map has keyframes 0.." + std::to_string(nKf - 1));
		m_sys->setStartKeyframe(static_cast<uint32_t>(o.startKf));
	}
}

void LocaliseRun::openLive(const std::string& camera, filters::TObjectFeed* feed)
{
	// Each channel read from a filtered rawlog, or made from the colour pair
	// on the system's threads (as processFrame would).
	std::vector<filters::TChannel> chans;
	for (const auto& l : m_sys->channelLabels()) chans.push_back(m_sys->channelSetup(l).channel);
	filters::TChannelFrameSourceOptions so;
	so.camera = camera;
	so.makeChannels = false;
	m_source = feed ? std::make_unique<filters::ChannelFrameSource>(std::move(*feed), chans, so)
					: std::make_unique<filters::ChannelFrameSource>(m_livePath, chans, so);
	for (size_t i = 0; i < chans.size(); i++) checkRecordedFilter(m_source->input(i), chans[i], m_livePath);
	m_first.emplace();
	if (!m_source->next(*m_first)) throw std::runtime_error(m_source->noFramesMessage());
	m_label = m_first->camera;
}

void checkRecordedFilter(const filters::TChannelInput& in, const filters::TChannel& ch, const std::string& rawlog)
{
	if (!in.filtered) return;
	// The map was checked against the config's filter: images another filter
	// made would not be what the map's channel compares with.
	const std::string what = "live rawlog '" + rawlog + "': its " + ch.label + " images '" + in.sensorLabel + "'";
	if (!in.recorded)
		throw std::runtime_error(
			what + " have no filter record" + (in.hasRecord ? " of suffix " + ch.suffix() : std::string()) +
			": how they were made is unknown (localise the colour original, or filter it again with shadyloc filter)");
	if (!in.recorded->sameImagesAs(*ch.filter))
		throw std::runtime_error(
			what + " were made with " + in.recorded->describe() + " (filter record), not with the config's [" +
			ch.label + "] " + ch.filter->describe() + " (localise the colour original, or filter it with the config)");
}

LocaliseRun::~LocaliseRun() = default;

void LocaliseRun::enableOracle(const io::Trajectory& gt)
{
	m_oracle = std::make_unique<Oracle>(*m_sys, gt);
	m_sys->setFrameHook([this](TLocalisationUpdate& u, const std::vector<features::TStereoFrame>& meas,
							   const geometry::TStereoCalib& calib) { m_oracle->probe(u, meas, calib); });
}

const std::vector<TLocalisationUpdate>& LocaliseRun::run(const std::function<void(const TLocalisationUpdate&)>& onFrame)
{
	if (!m_first) throw std::logic_error("LocaliseRun::run: called twice");
	m_ups.clear();
	filters::TChannelFrame fr = std::move(*m_first);
	m_first.reset();
	do
	{
		// A channel read is used as it is; one made from colour is made on
		// the system's thread for that channel.
		const auto images = [&](size_t i, cv::Mat& l, cv::Mat& r) {
			m_source->make(fr, i);
			l = fr.channels[i].left;
			r = fr.channels[i].right;
		};
		try
		{
			m_ups.push_back(m_sys->processChannels(images, fr.calib, fr.timestamp));
		}
		catch (const io::RawlogError&)
		{
			throw;	// names file and frame already
		}
		catch (const std::exception& e)
		{
			throw std::runtime_error(fr.where + e.what());
		}
		if (onFrame) onFrame(m_ups.back());
	} while (m_source->next(fr));
	return m_ups;
}

const filters::TChannelFrame& LocaliseRun::firstFrame() const
{
	if (!m_first) throw std::logic_error("LocaliseRun::firstFrame: the run has started");
	return *m_first;
}

}  // namespace shadyloc::localisation
