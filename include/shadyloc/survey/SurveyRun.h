/* ShadyLoc — a survey rawlog into a keyframe map, as one library call: what
 * `shadyloc survey` does between reading its options and saving the map,
 * shared with the leave-one-out evaluation (`shadyloc eval`, which surveys
 * every run once). The channels' frame sources walk the rawlog in lockstep;
 * the first channel's VO makes the keyframe chain (SurveyBuilder), and at
 * each map keyframe every channel's measurements are stored.
 */
#pragma once

#include <shadyloc/filters/Channel.h>
#include <shadyloc/geometry/StereoCamera.h>
#include <shadyloc/io/Trajectory.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/system/COutputLogger.h>

#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace shadyloc::survey
{
struct TSurveyRunOptions
{
	/** Channels to store; the first one's VO makes the keyframe chain. */
	std::vector<std::string> channels = {"mono", "invariant"};
	std::string sensorLabel;  //!< the colour stereo camera ("" = the first found)
	std::string runName;  //!< the survey run's name in the map ("" = the rawlog's stem)
	std::optional<io::Trajectory> gt;  //!< stored beside the keyframes, associated within 10 ms
	std::string gtName;	 //!< names the ground truth in errors
	std::string configName = "(no config)";	 //!< names the config in messages
	/** The channel whose VO bridges the chain VO's breaks (SurveyBuilder::
	 * bridge): "auto" is the second channel when there is one, "none" none. */
	std::string bridgeChannel = "auto";
};

struct TSurveyStats
{
	size_t frames = 0;	//!< stereo frames read
	size_t gtKeyframes = 0;	 //!< keyframes with a ground-truth pose
	size_t breaks = 0;	//!< breaks of the chain's VO
	size_t bridged = 0;	 //!< ... of them bridged by the bridge channel's VO (no new segment)
	double msTotal = 0;	 //!< reading, filters, VO, every channel's features [ms]
	geometry::TStereoCalib calib;  //!< of the first frame
	/** Per channel: mean frames in which the kept landmarks were re-found
	 * (empty unless landmarks are selected by re-observation). */
	std::vector<double> meanKeptReobservations;
	std::vector<double> refinedDepthShare;  //!< per channel: kept landmarks whose depth re-observations refined
};

class SurveyRun : public mrpt::system::COutputLogger
{
   public:
	/** Opens the rawlog's channels (the map options from cfg's [map]);
	 * throws naming the rawlog, the channel or the config at fault. */
	SurveyRun(const std::string& rawlog, const mrpt::config::CConfigFileBase& cfg, const TSurveyRunOptions& o);
	~SurveyRun() override;

	/** What is surveyed how: the channels, where their frames come from,
	 * the map options (what `shadyloc survey` prints before it starts). */
	void describe(std::ostream& out) const;

	/** Every frame of the rawlog; onFrame(frames so far, fraction of the
	 * file read) after each. Throws (naming file and frame) on unpaired
	 * channels, an empty run, a VO that never tracked, ground truth that
	 * matches no keyframe. The map is then complete (not yet saved). */
	CKeyframeMap::Ptr run(const std::function<void(size_t frames, double progress)>& onFrame = {});

	/** Warnings found while opening (e.g. a filtered rawlog whose images
	 * were made by another filter than the config's): the caller shows them. */
	const std::vector<std::string>& warnings() const { return m_warnings; }
	const TSurveyStats& stats() const { return m_stats; }
	/** The map being built (complete after run()). */
	const CKeyframeMap& map() const;
	const std::string& runName() const { return m_runName; }

   private:
	struct TImpl;
	std::unique_ptr<TImpl> m_impl;
	TSurveyStats m_stats;
	std::string m_runName;
	std::vector<std::string> m_warnings;
};

}  // namespace shadyloc::survey
