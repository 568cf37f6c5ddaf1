/* ShadyLoc — the combined localisation system (McManus et al. 2014,
 * Section III-B, Figure 4): live stereo VO on the monochrome channel predicts
 * for every localiser (the baseline's VO tells the invariant pipeline where
 * to look); the localisers (one StereoLocaliser per channel, made from
 * config) run in parallel threads on every frame; the policy takes the first
 * localiser in its order that has an accepted fix (monochrome, then
 * invariant), and when none has, dead-reckons on VO until one re-acquires.
 * The paper switched rather than fused because its invariant estimate is
 * noisier and slightly biased; with `joint` one more localiser
 * (JointLocaliser.h) solves both channels' correspondences together and
 * comes first, each landmark counting by its own geometry.
 *
 * Stages per frame: the channels' front end and the motion source
 * (extractChannel, voMotion, fallbackMotion), the predictor (predict) and
 * policy (Track, Track.h), the localisers, relocalisation (searchPlace).
 * With two threads the VO channel's localiser starts once its own VO has
 * the step, beside the other channels' front end
 * (frontEndOverlappingLocalisers). Starting and recovering: with no known
 * place, and on a frame without a fix after relocalise_after_frames (or
 * when every localiser is lost), every localiser's global search runs on
 * that frame, around dead reckoning or in the whole map; the first
 * verified, unambiguous place in policy order becomes the track, a new
 * hypothesis confirmed by K consistent frames (the place the first).
 *
 * The MRPT-facing call: feed CObservationStereoImages one at a time
 * (processObservation), read one TLocalisationUpdate per frame.
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/localisation/JointLocaliser.h>
#include <shadyloc/localisation/StereoLocaliser.h>
#include <shadyloc/localisation/Track.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/system/COutputLogger.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::localisation
{
/** Options of the combined system ([localise] in config/localise_sim.ini). */
struct TSystemOptions
{
	/** Localisers, in policy order (the first with an accepted fix is used). */
	std::vector<std::string> localisers = {"mono", "invariant"};
	/** Channels whose searches one more localiser solves together
	 * (JointLocaliser.h; its options [localiser.joint]); first in policy
	 * order. Runs only when every channel named is one of the localisers, so
	 * the baseline (`--localisers mono`) stays the paper's. Empty = none. */
	std::vector<std::string> joint;
	/** The joint solve runs only on frames where one of its channels'
	 * localisers has no accepted fix: where each channel holds alone, their
	 * fixes are used (the cross-check chooses among them) and the joint
	 * localiser's motion test starts from the frame's fix; where one
	 * channel is weak or none holds, the joint solve adds fixes and
	 * accuracy. */
	bool joint_only_where_a_channel_fails = true;
	/** Which of a channel's patch-pass matches the joint localiser takes
	 * (keepJointShare): a rejected solve's patches confirm the pose they
	 * were found at, right or not; under a wrong keyframe the union of such
	 * matches walked the track off (docs/localisation.md, "Injected faults"). */
	JointPatchMatches joint_patch_matches = JointPatchMatches::OfFixes;
	std::string vo_channel = "mono";  //!< the channel of the live VO that predicts for all
	/** A second live VO on this channel ("" = none) whose step replaces the
	 * VO channel's where that one could not measure the step (too few
	 * inliers, re-initialised): low sun in the lens defeats the monochrome VO
	 * where the invariant image still tracks. Runs only when the channel is
	 * one of the localisers, so the baseline (`--localisers mono`) stays the
	 * paper's baseline alone. */
	std::string vo_fallback_channel = "invariant";
	int threads = 2;  //!< 1: everything on the calling thread; >= 2: channels in parallel
	/** VO's covariance is scaled by this (the solver's is optimistic) [-]. */
	double vo_cov_scale = 4.0;
	/** A step VO could not measure (predicted by constant velocity) [m], [deg]. */
	double vo_lost_sigma_m = 0.3;
	double vo_lost_sigma_deg = 3.0;
	/** The track, its drift, confirmation and relocalisation (Track.h);
	 * keys vo_sigma_m_per_m, vo_sigma_deg_per_m (drift per metre since the
	 * last fix), confirmed_max_sigma_m, relocalise_after_frames,
	 * relocalise_window_m, global_search_after_frames,
	 * global_keyframes_per_frame, global_sigma_m,
	 * global_sigma_deg, seed_with_unconfirmed. */
	TTrackOptions track;

	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void load(const mrpt::config::CConfigFileBase& c, const std::string& section);
	void dump(std::ostream& out) const;
	void validate() const;
};

/** One frame's result: which localiser (if any), the pose relative to its
 * keyframe with covariance, quality, and each localiser's own result. */
struct TLocalisationUpdate
{
	size_t frame = 0;
	double timestamp = 0;  //!< [s]
	/** The localiser whose fix is used ("" when none: dead reckoning). */
	std::string used;
	bool localised() const { return !used.empty(); }
	/** A place is known (a fix now or earlier, dead-reckoned since): the
	 * pose fields below are meaningful. */
	bool placeKnown = false;
	uint32_t kf_id = 0;
	uint16_t kf_run = 0;
	uint64_t kf_frame = 0;
	double kf_stamp = 0;  //!< [s]
	Eigen::Isometry3d T_kf_live = Eigen::Isometry3d::Identity();  //!< live left camera in the keyframe's
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();  //!< of T_kf_live, left perturbation [m^2, rad^2]
	Eigen::Isometry3d T_map_live = Eigen::Isometry3d::Identity();  //!< live left camera in the map frame
	double distance_m = 0;	//!< travelled so far, from VO [m]
	int frames_since_fix = 0;
	std::vector<TLocaliserResult> localisers;  //!< in policy order
	vo::TFrameResult vo;
	/** The fallback VO's frame (default-constructed when no fallback VO runs). */
	vo::TFrameResult vo_fallback;
	TMotion motion;	 //!< VO's increment used for the prediction
	/** The VO channel whose step `motion` is ("" on the first frame). */
	std::string motion_from;
	bool track_confirmed = false;  //!< the prediction was of a confirmed place
	bool global_search = false;	 //!< the place was searched for on this frame (around dead reckoning or everywhere)
	SearchScope search_scope = SearchScope::None;
	TGlobalPlace place;	 //!< its outcome (the one adopted, or the first localiser's)
	/** The oracle bound of this frame (Oracle.h; empty unless evaluated):
	 * per localiser in policy order, 1 a true single-shot fix with the truth
	 * as prediction, 0 none, -1 no truth. */
	std::vector<int8_t> oracle;
	double ms_total = 0;  //!< channel conversion, features, VO, localisers and policy (decoding excluded) [ms]
	double ms_convert = 0;	//!< of which channel conversion, summed over the channels [ms]
	/** Of which the front end: conversion, features and the VO of every
	 * channel (with two threads: until every channel's features and the VO
	 * channel's VO are done; the fallback VO counts only where it ran before
	 * the prediction) [ms]. */
	double ms_front_end = 0;
	double ms_relocalise = 0;  //!< of which the place search of a frame without a fix [ms]
	/** With two threads: how long the thread that finished first waited for
	 * the other (0 on one thread) [ms]. */
	double ms_wait = 0;

	/** The localiser result of a channel, or nullptr. */
	const TLocaliserResult* result(const std::string& channel) const;
	/** T_kf_live and cov as MRPT's pose PDF. */
	mrpt::poses::CPose3DPDFGaussian pdf() const;
};

/** The keyframes a relocalisation searches around dead reckoning: those
 * within window_m along the map's chain from its keyframe, and those of any
 * segment within window_m of the dead-reckoned camera in the map frame,
 * facing within max_angle_deg of it (after a VO break of the survey the road
 * goes on in another segment); sorted by id. */
std::vector<uint32_t> keyframesAroundDeadReckoning(
	const CKeyframeMap& map, const TKeyframePose& deadReckoning, double window_m, double max_angle_deg);

class LocalisationSystem : public mrpt::system::COutputLogger
{
   public:
	/** A channel of the live frames. */
	struct TChannelSetup
	{
		filters::TChannel channel;	//!< makes the channel's grey images from the colour ones
		features::TStereoFeatureOptions features;
		TLocaliserOptions localiser;  //!< used if the channel is one of the localisers
	};

	/** Checks every channel's descriptor parameters against the map's
	 * (throws naming both sets) and that the map has the localisers'
	 * channels and keyframes. */
	LocalisationSystem(
		CKeyframeMap::Ptr map, const std::vector<TChannelSetup>& channels, const vo::TStereoVOOptions& vo,
		const TSystemOptions& o, const std::optional<vo::TStereoVOOptions>& voFallback = std::nullopt,
		const std::optional<TLocaliserOptions>& joint = std::nullopt);

	/** From a config: [localise], [localiser], [localiser.<channel>], [vo],
	 * [features] and their channel sections, the channel filter sections.
	 * `localisers`, if not empty, replaces [localise] localisers. `what`
	 * names the config in errors. */
	static std::unique_ptr<LocalisationSystem> FromConfig(
		const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::vector<std::string>& localisers,
		int threads, const std::string& what);

	/** What FromConfig reads, without a map: every options struct loaded and
	 * checked (a bad key or value throws as FromConfig would). */
	struct TSetup
	{
		std::vector<TChannelSetup> channels;  //!< the VO channel first
		vo::TStereoVOOptions vo;
		/** The fallback VO's options (its channel's [vo.<channel>]), when it runs. */
		std::optional<vo::TStereoVOOptions> voFallback;
		TSystemOptions system;
		/** The joint localiser's options ([localiser], [localiser.joint]), when it runs. */
		std::optional<TLocaliserOptions> joint;
	};
	static TSetup SetupFromConfig(
		const mrpt::config::CConfigFileBase& cfg, const std::vector<std::string>& localisers, int threads,
		const std::string& what);

	/** Starts near a keyframe: the first search for the place looks only at
	 * the keyframes within start_radius_m along the chain of it (a place is
	 * still verified geometrically, never assumed). */
	void setStartKeyframe(uint32_t id, double start_radius_m = 10.0);

	/** One stereo observation (images loaded, rectified). */
	TLocalisationUpdate processObservation(const mrpt::obs::CObservationStereoImages& obs);
	/** One stereo frame: colour images (as MRPT stores them, BGR) that each
	 * channel's filter converts. */
	TLocalisationUpdate processFrame(
		const cv::Mat& left, const cv::Mat& right, const geometry::TStereoCalib& calib, double timestamp);
	/** Gives channel i's grey pair (channelLabels() order) of the frame being
	 * processed; called once per channel, channels in parallel. */
	using ChannelImages = std::function<void(size_t channel, cv::Mat& left, cv::Mat& right)>;
	/** One stereo frame whose channels' images come from elsewhere (read from
	 * a filtered rawlog, or made by filters::ChannelFrameSource). */
	TLocalisationUpdate processChannels(
		const ChannelImages& images, const geometry::TStereoCalib& calib, double timestamp);

	/** Called at the end of every frame with its update and each channel's
	 * measurements (channelLabels() order): evaluation probes (Oracle.h). */
	using FrameHook = std::function<void(
		TLocalisationUpdate&, const std::vector<features::TStereoFrame>&, const geometry::TStereoCalib&)>;
	void setFrameHook(FrameHook hook) { m_hook = std::move(hook); }
	/** The localiser of a channel (nullptr: the channel only feeds the VO). */
	const StereoLocaliser* localiser(const std::string& label) const;
	/** The joint localiser (nullptr: none runs). */
	const JointLocaliser* jointLocaliser() const { return m_joint.get(); }

	const CKeyframeMap& map() const { return *m_map; }
	const TSystemOptions& options() const { return m_opts; }
	/** The channel labels, the VO's first. */
	std::vector<std::string> channelLabels() const;
	const TChannelSetup& channelSetup(const std::string& label) const;
	/** The live descriptor parameters of a channel (what the map must match). */
	map::TChannelParams liveParams(const std::string& label) const;
	static map::TChannelParams liveParams(const filters::TChannel& ch, const features::TStereoFeatureOptions& fo);
	void reset();

   private:
	struct TPipe
	{
		TChannelSetup setup;
		features::StereoFeatureExtractor extractor;
		std::unique_ptr<StereoLocaliser> localiser;  //!< null: the channel only feeds the VO
		int policyRank = -1;  //!< index in m_opts.localisers
	};
	/** One live VO and its previous frame. */
	struct TVOTrack
	{
		vo::StereoVO vo;
		size_t pipe = 0;  //!< the channel (m_pipes) it runs on
		bool havePrev = false;
		vo::TFrameResult prev;
		TVOTrack(const vo::TStereoVOOptions& o, const features::TStereoFeatureOptions& f) : vo(o, f) {}
		// The fallback VO runs on demand: where it is not needed it keeps
		// the frame as its standby, to start from when it is.
		struct TStandby
		{
			features::TStereoFrame meas;
			geometry::TStereoCalib calib;
			double timestamp = 0;
		};
		std::optional<TStandby> standby;
		bool trackedLast = false;  //!< it tracked the previous frame: it goes on from its own keyframe
	};
	/** The VO's increment from the previous frame with its covariance;
	 * `measured` tells whether the VO measured it (else a constant-velocity
	 * guess with vo_lost_sigma). Advances the track's previous frame. */
	TMotion motionOf(const vo::TFrameResult& r, TVOTrack& t, bool& measured) const;

	CKeyframeMap::Ptr m_map;
	TSystemOptions m_opts;
	std::vector<TPipe> m_pipes;	 //!< the VO channel first
	TVOTrack m_vo;
	std::unique_ptr<TVOTrack> m_voFallback;	 //!< null: no fallback VO
	std::optional<Eigen::Isometry3d> m_lastVoStep;	//!< the VO channel's last measured step (T_prev_curr)
	std::unique_ptr<JointLocaliser> m_joint;  //!< null: no joint localiser
	std::vector<size_t> m_jointPipes;  //!< the pipes whose searches it joins, in its channels' order
	/** Channel i's grey pair made and measured (meas[i]); its conversion time in msConvert[i]. */
	void extractChannel(
		size_t i, const ChannelImages& images, const geometry::TStereoCalib& calib, size_t frame,
		std::vector<features::TStereoFrame>& meas, std::vector<double>& msConvert);
	/** The VO channel's VO on its measurements: u.vo, u.motion; whether it measured the step. */
	bool voMotion(
		const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib, double timestamp,
		TLocalisationUpdate& u);
	/** The fallback VO on its channel's measurements, only where the VO
	 * channel did not measure its step: it starts from the frame before
	 * (kept as its standby; the VO channel's last measured step predicts the
	 * first step) and goes on while it is needed; its step replaces u.motion.
	 * Elsewhere the frame becomes its standby (at the end of the frame). */
	void fallbackMotion(
		const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib, double timestamp,
		bool voMeasured, TLocalisationUpdate& u);
	/** The predictor: the distance travelled, the track moved by u.motion,
	 * and the localisers' input made from them. */
	TLocaliserInput predict(const geometry::TStereoCalib& calib, double timestamp, TLocalisationUpdate& u);
	/** Localises channel i's measurements with the frame's input. */
	using LocaliseChannel = std::function<void(size_t, const TLocaliserInput&)>;
	/** The front end, the predictor and every channel localiser, in order on this thread. */
	TLocaliserInput frontEndThenLocalisers(
		const ChannelImages& images, const geometry::TStereoCalib& calib, double timestamp,
		std::vector<features::TStereoFrame>& meas, TLocalisationUpdate& u, const LocaliseChannel& localise);
	/** The same on two threads, the VO channel's localiser overlapping the
	 * other channels' front end (the same results). */
	TLocaliserInput frontEndOverlappingLocalisers(
		const ChannelImages& images, const geometry::TStereoCalib& calib, double timestamp,
		std::vector<features::TStereoFrame>& meas, TLocalisationUpdate& u, const LocaliseChannel& localise);
	/** Runs fn(i) for every localiser's pipe, the first on this thread and
	 * the others on a second one when threads >= 2. */
	template <typename F>
	void forLocalisers(F&& fn);
	/** The accepted fix the frame uses (chooseFix over the results in
	 * policy order), or null. */
	const TLocaliserResult* policyFix(const std::vector<const TLocaliserResult*>& inOrder) const;
	/** Marks the frame's accepted fixes that a more certain one contradicts
	 * (contradictedFixes) and makes their localisers forget them. */
	void rejectContradicted(std::vector<TLocaliserResult>& results);
	/** How fixes are compared with each other: the keyframe link and the
	 * prediction test's chi^2 of the localiser (channel or joint) that made `r`. */
	std::pair<KeyframeLink, double> comparisonOf(const TLocaliserResult& r) const;
	/** The accepted solve `r` as the track takes it (fused with the
	 * prediction while the track is confirmed). */
	TKeyframePose fusedFix(const TLocaliserResult& r, const TKeyframePose& pred, bool confirmed) const;
	/** Searches for the place (scope) and adopts the first verified one in
	 * policy order: a fix when it agrees with a confirmed track, or when it
	 * is the K-th agreeing place of an unconfirmed hypothesis; else a new
	 * hypothesis, or the next consistent frame of the one it agrees with. */
	void searchPlace(
		SearchScope scope, const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib,
		const std::vector<size_t>& order, TLocalisationUpdate& u);

	// State.
	size_t m_frame = 0;
	Track m_track;
	std::vector<uint32_t> m_searchAmong;  //!< keyframes a whole-map search looks at (empty: all)
	MapSweep m_sweep;  //!< ... the map's slice for each search, where m_searchAmong is empty
	FrameHook m_hook;
	double m_distance = 0;
};

}  // namespace shadyloc::localisation
