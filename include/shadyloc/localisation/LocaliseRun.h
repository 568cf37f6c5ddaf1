/* ShadyLoc — one localisation run as a library call, and its output files:
 * a live rawlog against a keyframe map with the combined system (or the
 * baseline alone), evaluated, written as frames.csv, trajectory.tum,
 * summary.json and timing.json (docs/localisation.md, "Outputs"). What
 * `shadyloc localise` does between its options and its output directory,
 * shared with the leave-one-out evaluation (`shadyloc eval`), which runs it
 * for every (live, map, system) pair.
 */
#pragma once

#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/localisation/Evaluation.h>
#include <shadyloc/localisation/LocalisationSystem.h>

#include <mrpt/config/CConfigFileBase.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace shadyloc::localisation
{
/** summary.json's format version (docs/localisation.md). */
constexpr int kSummaryVersion = 1;

/** Sections a localise config may hold: the VO config's ([vo], [features],
 * their per-channel overrides, [map], [filters], the channels' filter
 * sections), [localise], [localiser], [localiser.<channel>]. Throws
 * core::SettingsError naming the first other section; `what` names the
 * config. */
void checkLocaliseSections(const mrpt::config::CConfigFileBase& cfg, const std::string& what);

/** Loads every options struct a localisation run reads from cfg (the
 * system's, each channel's filter, features, localiser, the VO's) without a
 * map, so that a bad key or value is reported before any work. `localisers`
 * as in CLocalisationSystem::FromConfig. Throws like FromConfig. */
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

class COracle;

/** One live run against one map. */
class CLocaliseRun
{
   public:
	/** Checks the config's sections, makes the system (descriptor
	 * parameters checked against the map's), opens the live rawlog's frame
	 * source (each channel read from a filtered rawlog with the config's
	 * filter record, or made from the colour pair) and reads its first
	 * frame. Errors name the map, the config, the rawlog and frame. */
	CLocaliseRun(
		const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::string& mapPath,
		const std::string& livePath, const TLocaliseRunOptions& o);
	~CLocaliseRun();

	CLocalisationSystem& system() { return *m_sys; }
	const CLocalisationSystem& system() const { return *m_sys; }
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
	void openLive(const std::string& camera);

	std::unique_ptr<CLocalisationSystem> m_sys;
	std::unique_ptr<COracle> m_oracle;
	std::unique_ptr<filters::ChannelFrameSource> m_source;
	std::optional<filters::TChannelFrame> m_first;	//!< read by the constructor
	std::string m_livePath, m_label;
	std::vector<TLocalisationUpdate> m_ups;
};

/** Throws naming the rawlog if channel `ch` is read from derived images
 * that no filter record describes, or that another filter than `ch`'s made. */
void checkRecordedFilter(const filters::TChannelInput& in, const filters::TChannel& ch, const std::string& rawlog);

/** Where a run's inputs came from, for summary.json's provenance. */
struct TLocaliseProvenance
{
	std::string program = "shadyloc localise";
	std::string buildCommit = "unknown";  //!< the program's commit (written at build time; "-dirty" when built from modified sources)
	std::string configWhat, configText;	 //!< config names, their concatenated text (hashed)
	std::string mapPath, livePath, gtPath;	//!< as given; gtPath "" without ground truth
	std::string mapHash, liveHash, gtHash;	//!< fnv1a64File of each ("" = computed from the path)
	int startKf = -1;
};

/** frames.csv: one row per live frame (docs/localisation.md). */
void writeFramesCsv(
	const std::string& path, const std::vector<TLocalisationUpdate>& ups, const TEvaluation& ev, const CKeyframeMap& map);
/** solves.csv, the solve log: one row per localiser and frame with a solve,
 * accepted or not, with what the accept stage saw and, with ground truth,
 * its error and NEES (docs/localisation.md, "The solve log"). */
void writeSolvesCsv(const std::string& path, const std::vector<TLocalisationUpdate>& ups, const TEvaluation& ev);
/** trajectory.tum: the live left camera in the map frame where a place is known. */
void writeTrajectory(const std::string& path, const std::vector<TLocalisationUpdate>& ups);
/** summary.json's text (versioned; no times: it compares byte for byte). */
std::string summaryJson(
	const std::vector<TLocalisationUpdate>& ups, const TEvaluation& ev, const TSystemOptions& sys,
	const TLocaliseProvenance& prov);
/** timing.json's text: per-frame times, median and 95th percentile. */
std::string timingJson(const std::vector<TLocalisationUpdate>& ups, int threads);

/** FNV-1a, 64 bit, as 16 hex digits: of a file's bytes (throws naming an
 * unreadable file), of a text. The provenance's input hashes. */
std::string fnv1a64File(const std::string& path);
std::string fnv1a64(const std::string& text);
/** A JSON string literal; a number with `prec` decimals ("null" if not finite). */
std::string jsonString(const std::string& s);
std::string jsonNumber(double v, int prec = 6);
/** Writes text to path atomically (io::writeAtomically), throwing naming it. */
void writeTextFile(const std::string& path, const std::string& text);

}  // namespace shadyloc::localisation
