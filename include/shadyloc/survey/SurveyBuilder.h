/* ShadyLoc — building a keyframe map from a survey run: one VO chain (the
 * monochrome VO's, the more accurate) decides where the map's keyframes are;
 * at those frames every channel's stereo measurements are stored, so both
 * localisers localise against the same keyframe poses (McManus et al. 2014,
 * Section II). Map keyframes are chosen by the map's own spacing options,
 * independent of the VO's internal keyframes; the relative transform between
 * consecutive map keyframes and its covariance are composed along the VO's
 * keyframe chain. A VO re-initialisation (a break) starts a new segment.
 *
 * The `survey` area joins the VO (which makes the chain) and the map (which
 * stores it): the map holds the keyframe data type the VO fills, so `vo`
 * includes `map`, and the builder, which needs both, cannot live in `map`
 * without a cycle (docs/architecture.md).
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/CObservationFilter.h>
#include <shadyloc/geometry/LandmarkDepth.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/system/COutputLogger.h>

#include <optional>

namespace shadyloc::survey
{
/** What the map records of a channel: the filter that made its images (for
 * a filtered rawlog the filter its record names, not the config's) and the
 * feature options the channel's descriptors were made with. */
map::TChannelParams channelParams(
	const std::string& label, const CObservationFilter& madeBy, const features::TStereoFeatureOptions& fo);

/** Keeps at most `keep` measurements (all if keep <= 0 or fewer), spread
 * over the image: the image is cut into cols x rows buckets and the buckets
 * take turns giving up their best remaining landmark, so the kept landmarks
 * cover the view instead of clustering on the most textured object. "Best":
 * the higher `score` when given (one per measurement, e.g. its
 * re-observations), then the FAST response, then the stereo correlation.
 * With a score, landmarks scoring below `minScore` are never kept. Order of
 * the result: by bucket round, stable. */
std::vector<features::TStereoMeasurement> selectLandmarks(
	const std::vector<features::TStereoMeasurement>& all, int keep, int cols, int rows, int width, int height,
	const std::vector<int>* score = nullptr, int minScore = 0);

/** selectLandmarks as indices into `all`. */
std::vector<size_t> selectLandmarkIndices(
	const std::vector<features::TStereoMeasurement>& all, int keep, int cols, int rows, int width, int height,
	const std::vector<int>* score = nullptr, int minScore = 0);

/** A survey frame that re-observes a keyframe: its measurements (and the
 * left image they were cut from) and the keyframe's pose in it. */
struct TReobservingFrame
{
	const features::TStereoFrame* frame = nullptr;
	Eigen::Isometry3d T_frame_kf = Eigen::Isometry3d::Identity();  //!< from the survey's VO chain
};

/** How landmarks are re-found: the VO's own keyframe matcher (BRIEF in a
 * circle around the projection at the VO's pose, the keyframe patch refined
 * in the frame) and its relative-pose estimator (RANSAC seeded with the VO's
 * pose, robust solve): a landmark counts in a frame when it is matched and an
 * inlier of the solve. */
struct TReobservationMatching
{
	vo::TKeyframeMatcherOptions matcher;
	vo::TRelativePoseOptions pose;
	/** From the survey's VO options and the map's search radius. */
	static TReobservationMatching From(const vo::TStereoVOOptions& vo, double radius_px);
};

/** Per landmark of `landmarks` (a keyframe's measurements, calibration
 * `calib`): in how many of `frames` it is re-found (see
 * TReobservationMatching). A frame whose solve fails credits nothing. */
std::vector<int> countReobservations(
	const std::vector<features::TStereoMeasurement>& landmarks, const geometry::TStereoCalib& calib,
	const std::vector<TReobservingFrame>& frames, const TReobservationMatching& m);

/** Per landmark, each re-observation that countReobservations counts: the
 * frame's solved pose relative to the keyframe (with its covariance) and
 * the landmark's measurement there, for the depth refinement. */
std::vector<std::vector<geometry::TDepthObservation>> findReobservations(
	const std::vector<features::TStereoMeasurement>& landmarks, const geometry::TStereoCalib& calib,
	const std::vector<TReobservingFrame>& frames, const TReobservationMatching& m);

/** Builds a map from a survey run, one frame at a time:
 *
 *     for each frame:  offer(res, ...)              every frame, tracked or not
 *                      addFrame(per-channel frames) if offer() saw a tracked frame and needsFrames()
 *                      addKeyframe(...)             if offer() returned true
 *     at the end:      finish()
 *
 * With landmark_selection = reobserved a keyframe waits until the survey has
 * passed reobservation_window_m beyond it (or its chain segment ended): its
 * landmarks are then scored by countReobservations against the tracked
 * frames of its segment within the window before and after it, and thinned
 * by selectLandmarks with that score. Otherwise a keyframe is thinned by the
 * strongest corners and appended at once. */
class SurveyBuilder : public mrpt::system::COutputLogger
{
   public:
	/** The map must be set up (CKeyframeMap::setup); its options give the
	 * keyframe spacing and the landmark selection. `vo`: the options of the
	 * VO that makes the chain (its matcher and pose estimator re-find
	 * landmarks for the reobserved selection). */
	SurveyBuilder(CKeyframeMap& map, const std::string& runName, const vo::TStereoVOOptions& vo = {});

	/** After the chain's VO processed a frame: `res` its result,
	 * `voKeyframes` the VO's keyframes now, `voKeyframesBefore` their count
	 * before the frame. True when this frame becomes a map keyframe: then
	 * call addKeyframe() with every channel's measurements of this frame. */
	bool offer(const vo::TFrameResult& res, const std::vector<vo::TKeyframe>& voKeyframes, size_t voKeyframesBefore);

	/** The frame offer() just accepted opens a new segment after a break of
	 * the chain's VO (bridgeable()): `T_last_f`, its pose in the last map
	 * keyframe measured by another channel's VO that tracked through the
	 * break, links it to that keyframe instead, so the segment goes on
	 * (addKeyframe places it and the chain's later keyframes by this link). */
	bool bridgeable() const;
	void bridge(const geometry::TPoseWithCov& T_last_f);
	size_t bridged() const { return m_bridged; }  //!< breaks bridged by bridge()

	/** Whether the builder needs every tracked frame's measurements (addFrame):
	 * to score landmarks or to refine their depth. */
	bool needsFrames() const;
	/** Whether landmarks are thinned by their re-observation count. */
	bool scoresLandmarks() const;
	/** The frame last offered (tracked), every channel's measurements in the
	 * map's channel order, for re-observation; ignored when !needsFrames()
	 * or the frame was not tracked. */
	void addFrame(std::vector<features::TStereoFrame> perChannel);

	/** Adds the frame last offered (and accepted) with its measurements per
	 * channel (in the map's channel order), thinned by selectLandmarks, and
	 * its ground-truth pose if known. The keyframe reaches the map now
	 * (strongest) or once the frames after it are known (reobserved). */
	void addKeyframe(
		const std::vector<std::vector<features::TStereoMeasurement>>& perChannel,
		const std::optional<Eigen::Isometry3d>& T_gt_kf = std::nullopt);

	/** Appends the keyframes still waiting for their re-observations. */
	void finish();

	size_t breaks() const { return m_breaks; }	//!< VO breaks seen (new segments)
	/** Mean re-observations per kept landmark, per channel (reobserved only). */
	std::vector<double> meanKeptReobservations() const;
	/** Per channel: the share of kept landmarks whose depth the re-observations
	 * refined (TKeyframeMapOptions::depth_from_reobservations). */
	std::vector<double> refinedDepthShare() const;

   private:
	CKeyframeMap& m_map;
	uint16_t m_run;
	size_t m_breaks = 0;
	size_t m_bridged = 0;
	bool m_haveOrigin = false;
	size_t m_added = 0;	 //!< keyframes added by this builder (appended or waiting)
	Eigen::Isometry3d m_T_world_map = Eigen::Isometry3d::Identity();  //!< VO world -> map frame
	uint32_t m_segment = 0;
	bool m_segmentOpen = false;	 //!< a map keyframe exists in the current segment
	bool m_predictedSegment = false;  //!< the current segment started after a break
	// The last map keyframe, as seen by the VO chain: reference VO keyframe and pose in it.
	size_t m_lastRef = 0;
	Eigen::Isometry3d m_T_ref_last = Eigen::Isometry3d::Identity();
	geometry::Matrix6d m_cov_ref_last = geometry::Matrix6d::Zero();
	Eigen::Isometry3d m_T_map_last = Eigen::Isometry3d::Identity();
	// The frame accepted by offer(), waiting for addKeyframe().
	struct TPending
	{
		bool valid = false;
		vo::TFrameResult res;
		size_t ref = 0;
		Eigen::Isometry3d T_ref_f = Eigen::Isometry3d::Identity();
		geometry::Matrix6d cov_ref_f = geometry::Matrix6d::Zero();
		Eigen::Isometry3d T_prev_f = Eigen::Isometry3d::Identity();
		geometry::Matrix6d cov_prev_f = geometry::Matrix6d::Zero();
		bool newSegment = false;
		bool bridged = false;  //!< newSegment, but linked by bridge()
	} m_pending;

	// ---- re-observation ----------------------------------------------------------
	TReobservationMatching m_matching;
	// The VO chain frame by frame: its segment (a new one at First/Reinit)
	// and the path distance along it.
	uint32_t m_voSegment = 0;
	double m_voDist = 0;  //!< [m]
	bool m_voStarted = false;  //!< the VO chain had its first frame
	bool m_lastTracked = false;	 //!< the frame last offered was tracked
	uint64_t m_lastFrame = 0;  //!< index of the frame last offered
	Eigen::Isometry3d m_T_world_lastTracked = Eigen::Isometry3d::Identity();
	struct TFrame
	{
		uint64_t frame = 0;
		uint32_t voSegment = 0;
		double dist = 0;  //!< [m] along the VO chain
		Eigen::Isometry3d T_world = Eigen::Isometry3d::Identity();
		std::vector<features::TStereoFrame> channels;
	};
	std::vector<TFrame> m_frames;  //!< tracked frames still within reach of a keyframe
	struct TWaiting
	{
		map::TMapKeyframe kf;  //!< all measurements, not yet thinned
		uint32_t voSegment = 0;
		double dist = 0;  //!< [m]
		Eigen::Isometry3d T_world = Eigen::Isometry3d::Identity();
	};
	std::vector<TWaiting> m_waiting;
	std::vector<double> m_keptSum, m_keptCount;	 //!< per channel, for meanKeptReobservations
	std::vector<double> m_refined;	//!< per channel, kept landmarks with a refined depth

	void flush(bool all);
	void append(TWaiting w);
};

}  // namespace shadyloc::survey
