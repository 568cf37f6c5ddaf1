/* ShadyLoc — a keyframe of the VO: a pose in its keyframe chain and the
 * stereo measurements of one image channel made there. The VO creates them
 * (one chain per channel run); the survey (SurveyBuilder) turns the chain's
 * keyframes into the map's own records, so `vo` and `map` do not know each
 * other. Not stored as such: the map's format (docs/map.md) is the one codec. */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/geometry/PoseSolver.h>

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace shadyloc::vo
{
/** A keyframe of one channel: where it is in the chain and what it saw. */
struct TKeyframe
{
	uint32_t id = 0;  //!< 0, 1, 2, ... in creation order
	size_t frame = 0;  //!< index of the source frame it was made from
	double timestamp = 0;  //!< [s]
	/** Pose of this keyframe's left camera in the previous keyframe's left camera
	 * (identity for the first). */
	Eigen::Isometry3d T_prevkf_kf = Eigen::Isometry3d::Identity();
	/** Covariance of T_prevkf_kf, left perturbation (translation, rotation)
	 * [m^2, rad^2] (geometry/PoseSolver.h). */
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();
	/** True if T_prevkf_kf is a prediction across a tracking gap (Reinit), not a
	 * measurement: the chain is broken here and cov is large. */
	bool chain_break = false;
	/** Pose in the first keyframe's frame (the product of the chain), for convenience. */
	Eigen::Isometry3d T_world_kf = Eigen::Isometry3d::Identity();
	std::vector<features::TStereoMeasurement> meas;	 //!< landmarks in this keyframe's frame
};

}  // namespace shadyloc::vo
