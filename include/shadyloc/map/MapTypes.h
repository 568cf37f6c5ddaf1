/* ShadyLoc — what the dual-channel keyframe map stores (McManus et al. 2014,
 * Section II: the survey's "visual memory"): keyframes of one VO chain, each
 * with the stereo measurements of every channel (monochrome, invariant) at
 * the same frame, and the parameters that define those measurements.
 *
 * Frames: the map frame is the first keyframe's left camera (x right, y down,
 * z forward, metres). Each keyframe stores T_map_kf (the chain's product) and
 * T_prev_kf with its 6x6 covariance (left perturbation, (translation,
 * rotation), geometry/PoseSolver.h). After a VO break the keyframes start a
 * new segment whose T_map_kf is only predicted (`predicted` set). docs/map.md.
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/geometry/PoseSolver.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace shadyloc::map
{
/** The parameters that define a channel's descriptors: the observation
 * filter that made its images (filters/Channel.h: a channel is that filter)
 * and the feature options that shape the descriptor (its kind, BRIEF's
 * pattern or ORB's pyramid). A live run whose values differ
 * produces descriptors that do not compare with the map's. The map knows the
 * filter by class name and image options only (it does not depend on the
 * filters): the filter can be rebuilt from them through the class factory. */
struct TChannelParams
{
	std::string label;	//!< the channel's name, e.g. "mono", "invariant"
	/** Class of the filter that made the channel's images ("CFilterInvariant"). */
	std::string filter_class;
	/** That filter's image options (CObservationFilter::imageOptionsAsIni():
	 * canonical "key = value" lines, e.g. the invariant transform and its
	 * 8-bit mapping); equal text means equal images. */
	std::string filter_options;
	int brief_patch_size = 32;	//!< BRIEF patch side [px]
	uint32_t brief_seed = 0x5ad710c;  //!< BRIEF test pattern seed
	double presmooth_sigma = 0;	 //!< Gaussian pre-smoothing before detection [px], 0 = off
	/** Detector and descriptor (map format 4; older maps are all BRIEF). */
	features::DescriptorKind descriptor = features::DescriptorKind::Brief;
	int orb_levels = 8;	 //!< ORB pyramid levels (descriptor-defining with ORB only)
	double orb_scale_factor = 1.2;	//!< ORB level size ratio (descriptor-defining with ORB only)
	/** Pixel noise of (uL, v, uR) behind the landmark covariances [px] (not
	 * descriptor-defining: landmark covariances are recomputed with it on load). */
	double sigma_px = 0.5;

	/** From the filter that made the images (class name, image options) and
	 * the feature options a survey or a live run uses for this channel. */
	static TChannelParams From(
		const std::string& label, const std::string& filterClass, const std::string& filterOptions,
		const features::TStereoFeatureOptions& fo);

	/** The filter options as "key=value" pairs on one line. */
	std::string filterOptionsLine() const;
	/** One line, every descriptor-defining value. */
	std::string asString() const;
	/** Names of the descriptor-defining fields that differ ("" when none):
	 * filter class, each filter option that differs or is missing on one
	 * side ("filter option alpha"), the descriptor kind ("descriptor: map
	 * brief, live orb"), BRIEF patch size and seed (both BRIEF), ORB levels
	 * and scale factor (both ORB), pre-smoothing. */
	std::string differences(const TChannelParams& o) const;
	bool operator==(const TChannelParams& o) const;
};

/** One keyframe of the map. */
struct TMapKeyframe
{
	uint32_t id = 0;  //!< index in the map
	uint16_t run = 0;  //!< survey run (index into CKeyframeMap::runs())
	uint32_t segment = 0;  //!< chain segment, a new one after each VO break (map-wide counter)
	uint64_t frame = 0;	 //!< index of the source frame in its survey run
	double timestamp = 0;  //!< [s]
	/** T_map_kf is a prediction across a VO break (this keyframe's segment did
	 * not start at the map origin): use it to search, never as a measured pose. */
	bool predicted = false;
	Eigen::Isometry3d T_map_kf = Eigen::Isometry3d::Identity();	 //!< left camera in the map frame
	/** Left camera in the previous keyframe's left camera (identity for the
	 * first keyframe of a run); across a break, a prediction. */
	Eigen::Isometry3d T_prev_kf = Eigen::Isometry3d::Identity();
	/** Covariance of T_prev_kf, left perturbation (translation, rotation) [m^2, rad^2]. */
	geometry::Matrix6d cov_prev_kf = geometry::Matrix6d::Zero();
	/** Stereo measurements per channel (indexed like CKeyframeMap::channels()),
	 * landmarks in this keyframe's left camera frame. */
	std::vector<std::vector<features::TStereoMeasurement>> channels;
	/** Ground-truth pose of the left camera in the ground truth's world frame,
	 * if the survey had one. Evaluation only: localisation never reads it. */
	std::optional<Eigen::Isometry3d> T_gt_kf;
};

/** A keyframe found by a spatial query. */
struct TKeyframeHit
{
	uint32_t id = 0;
	double distance_m = 0;	//!< between the camera centres [m]
	double angle_deg = 0;  //!< between the optical axes [deg]
};

/** Parameters of CKeyframeMap's nearest-keyframe query. */
struct TNearestQuery
{
	double max_distance_m = 5.0;  //!< camera centres within this [m]
	double max_angle_deg = 30.0;  //!< optical axes within this: roads are driven both ways [deg]
	size_t max_results = 5;	 //!< best first (by distance + angle_weight_m_per_deg * angle)
	double angle_weight_m_per_deg = 0.1;  //!< ranking: metres a degree of heading is worth [m/deg]
	bool include_predicted = true;	//!< also keyframes whose map pose is only predicted
	/** Only keyframes whose poses share a frame with this keyframe's (an
	 * experience linked nowhere has a frame of its own); -1: any. A query
	 * pose is always in some keyframe's frame: pass that keyframe. */
	int64_t same_frame_as = -1;
};

/** A verified relative pose between keyframes of two experiences (survey
 * runs of one map): keyframe b's left camera in keyframe a's, from
 * localising b's run against the map that held a (`survey --append`). */
struct TExperienceLink
{
	uint32_t a = 0, b = 0;	//!< map keyframe ids, of different runs
	Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();  //!< of T_a_b, left perturbation [m^2, rad^2]
};

/** The pose of one keyframe in another's frame, composed along the chain. */
struct TRelativePose
{
	Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  //!< keyframe b's left camera in a's [m]
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();  //!< of T_a_b, left perturbation [m^2, rad^2]
	double chain_length_m = 0;	//!< distance along the chain between a and b [m]
};

/** The queries a localiser makes of a keyframe map (MOLA's
 * KeyframeMapCapable shape: a small interface beside CMetricMap rather than
 * computeObservationLikelihood). Ids are keyframe indices. */
class KeyframeQueries
{
   public:
	virtual ~KeyframeQueries() = default;

	virtual size_t keyframeCount() const = 0;
	virtual const TMapKeyframe& keyframe(uint32_t id) const = 0;
	/** Index of a channel by its label; throws std::out_of_range naming the
	 * label and the map's channels if there is none. */
	virtual size_t channelIndex(const std::string& label) const = 0;

	/** Keyframes near a query pose in the map frame, heading included, best
	 * first (spatial index: a hash grid over camera centres). */
	virtual std::vector<TKeyframeHit> nearestKeyframes(
		const Eigen::Isometry3d& T_map_query, const TNearestQuery& q = {}) const = 0;

	/** Keyframes of id's run and segment within back_m behind and ahead_m
	 * ahead of it along the chain (distance along the path), in chain order,
	 * id included. */
	virtual std::vector<uint32_t> keyframesAlongChain(uint32_t id, double back_m, double ahead_m) const = 0;

	/** A keyframe's measurements of one channel (landmarks in its left camera). */
	virtual const std::vector<features::TStereoMeasurement>& measurements(
		uint32_t id, const std::string& channel) const = 0;

	/** Whether two keyframes are linked by measured transforms (same run and segment). */
	virtual bool sameSegment(uint32_t a, uint32_t b) const = 0;

	/** T_a_b composed along the chain with its covariance propagated. Throws
	 * std::invalid_argument naming both keyframes when they are not in one
	 * segment (a break is never silently chained). */
	virtual TRelativePose relativePose(uint32_t a, uint32_t b) const = 0;
};

}  // namespace shadyloc::map
