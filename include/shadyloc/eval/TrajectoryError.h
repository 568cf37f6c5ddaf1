/* ShadyLoc — trajectory error against ground truth: timestamp association,
 * rigid SE(3) alignment without scale (Horn 1987 / Umeyama 1991), absolute
 * trajectory error (ATE), relative pose error (RPE, Sturm et al. IROS 2012),
 * and KITTI-style drift (Geiger et al. CVPR 2012): translational [%] and
 * rotational [deg/m] error over sub-sequences of fixed path length.
 */
#pragma once

#include <shadyloc/io/Trajectory.h>

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace shadyloc::eval
{
// The metrics work on the library's one trajectory type (io/Trajectory.h);
// TUM files are read and written by io/Tum.h.
using io::TStampedPose;
using io::Trajectory;

/** Timestamp association (io::associate, where it lives). */
using io::associate;

struct TSegmentError
{
	double length = 0;	//!< sub-sequence length [m]
	int count = 0;	//!< sub-sequences evaluated
	double trans_pct = 0;  //!< mean translational error [% of length]
	double rot_deg_per_m = 0;  //!< mean rotational error [deg/m]
};

struct TTrajectoryErrors
{
	size_t matched = 0;	 //!< associated pose pairs
	double path_length = 0;	 //!< ground-truth path length over the matched poses [m]
	Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();	 //!< the alignment
	double ate_rmse = 0, ate_mean = 0, ate_max = 0;	 //!< [m], after alignment
	double rpe_trans_rmse = 0;	//!< per-step relative translation error RMSE [m]
	double rpe_rot_rmse_deg = 0;  //!< per-step relative rotation error RMSE [deg]
	std::vector<TSegmentError> segments;  //!< per sub-sequence length
	double kitti_trans_pct = 0;	 //!< mean over all segments of all lengths [%]
	double kitti_rot_deg_per_m = 0;	 //!< [deg/m]
	double length_scale = 1;  //!< factor applied to 100..800 m (1 for runs >= 1 km)
	std::string asText() const;	 //!< human-readable report
};

/** Errors of est against gt. Sub-sequence lengths: 100, 200, ..., 800 m as
 * in KITTI, multiplied by min(1, L / 1000 m) for a run of length L so that a
 * short run still has several lengths (the longest ~0.8 L). */
TTrajectoryErrors computeErrors(const Trajectory& gt, const Trajectory& est, double maxDt = 0.02);

}  // namespace shadyloc::eval
