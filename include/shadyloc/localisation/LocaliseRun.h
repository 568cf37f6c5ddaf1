/* ShadyLoc — one localisation run as a library call: a live rawlog against
 * a keyframe map with the combined system (or the baseline alone). What
 * `shadyloc localise` does between its options and its output directory,
 * shared with the leave-one-out evaluation (`shadyloc eval`), which runs it
 * for every (live, map, system) pair; the evaluation and the output files
 * (frames.csv, summary.json, ...) are the eval area's
 * (eval/Evaluation.h, eval/LocaliseOutputs.h).
 */
#pragma once

#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/io/Trajectory.h>
#include <shadyloc/localisation/LocalisationSystem.h>

#include <mrpt/config/CConfigFileBase.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace shadyloc::localisation
{
/** Sections a localise config may hold: the VO config's ([vo], [features],
 * their per-channel overrides, [map], [filters], the channels' filter
 * sections), [localise], [localiser], [localiser.<channel>]. Throws
 * core::SettingsError naming the first other section; `what` names the
 * config. */
void checkLocaliseSections(const mrpt::config::CConfigFileBase& cfg, const std::string& what);

/** Loads every options struct a localisation run reads from cfg (the
 * system's, each channel's filter, features, localiser, the VO's) without a
 * map, so that a bad key or value is reported before any work. `localisers`
 * as in LocalisationSystem::FromConfig. Throws like FromConfig. */
void checkLocaliseConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::vector<std::string>& localisers, const std::string& what);

struct TLocaliseRunOptions
{
	std::vector<std::string> localisers;  //!< policy order; empty: [localise] localisers
	int threads = 0;  //!< 0: [localise] threads
	int startKf = -1;  //!< >= 0: start at this map keyframe instead of by global search
	std::string sensorLabel;  //!< the live camera ("" = the first colour camera, or that of the derived channels)
	std::string configWhat = "(no config)";	 //!< names the config in errors
};

class Oracle;

/** One live run against one map. */
class LocaliseRun
{
   public:
	/** Checks the config's sections, makes the system (descriptor
	 * parameters checked against the map's), opens the live rawlog's frame
	 * source (each channel read from a filtered rawlog with the config's
	 * filter record, or made from the colour pair) and reads its first
	 * frame. Errors name the map, the config, the rawlog and frame. */
	LocaliseRun(
		const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::string& mapPath,
		const std::string& livePath, const TLocaliseRunOptions& o);
	/** The same with frames as they arrive (a live camera): colour stereo
	 * observations from `feed`, channels made from them. Waits for the
	 * first frame. */
	LocaliseRun(
		const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::string& mapPath,
		filters::TObjectFeed feed, const TLocaliseRunOptions& o);
	~LocaliseRun();

	LocalisationSystem& system() { return *m_sys; }
	const LocalisationSystem& system() const { return *m_sys; }
	const std::string& sensorLabel() const { return m_label; }

	/** Every frame of the live rawlog; onFrame after each. Throws naming
	 * file, object and frame. Once only. */
	const std::vector<TLocalisationUpdate>& run(const std::function<void(const TLocalisationUpdate&)>& onFrame = {});
	/** The live run's first frame, before run() (its camera, for checks). */
	const filters::TChannelFrame& firstFrame() const;
	/** Where channel i (channelLabels() order) comes from. */
	const filters::ChannelFrameSource& source() const { return *m_source; }
	const std::vector<TLocalisationUpdate>& updates() const { return m_ups; }
	/** Probes every frame for the oracle bound against `gt` (Oracle.h;
	 * evaluation only: the system never sees it). */
	void enableOracle(const io::Trajectory& gt);

   private:
	void makeSystem(
		const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::string& mapPath,
		const TLocaliseRunOptions& o);
	/** From the rawlog m_livePath, or from `feed` when given. */
	void openLive(const std::string& camera, filters::TObjectFeed* feed);

	std::unique_ptr<LocalisationSystem> m_sys;
	std::unique_ptr<Oracle> m_oracle;
	std::unique_ptr<filters::ChannelFrameSource> m_source;
	std::optional<filters::TChannelFrame> m_first;	//!< read by the constructor
	std::string m_livePath, m_label;
	std::vector<TLocalisationUpdate> m_ups;
};

/** Throws naming the rawlog if channel `ch` is read from derived images
 * that no filter record describes, or that another filter than `ch`'s made. */
void checkRecordedFilter(const filters::TChannelInput& in, const filters::TChannel& ch, const std::string& rawlog);

}  // namespace shadyloc::localisation
