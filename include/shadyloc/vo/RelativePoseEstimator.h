/* ShadyLoc — the relative-pose estimator: a stage of the stereo VO that the
 * localisers reuse. From correspondences between a reference frame's
 * landmarks and the current frame's stereo measurements:
 *   1. RANSAC (geometry::ransacStereoPose): the given hypotheses (the motion
 *      prior's prediction) scored first, then 3-point minimal sets, each new
 *      best locally optimised;
 *   2. a robust solve on the inliers: two-view bundle adjustment
 *      (geometry::solveStereoPoseTwoView) or fixed landmarks
 *      (geometry::solveStereoPose);
 *   3. inliers re-selected at the solution and solved once more;
 *   4. the covariance of T_ref_curr (left perturbation, translation first).
 * Without a prediction in the input the pose is solved without the motion
 * prior (what a localiser's failure test compares against).
 */
#pragma once

#include <shadyloc/geometry/PoseSolver.h>
#include <shadyloc/geometry/StereoCamera.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace shadyloc::vo
{
/** Options of RelativePoseEstimator (the VO fills them from TStereoVOOptions,
 * see poseEstimatorOptionsFrom()). */
struct TRelativePoseOptions
{
	double ransac_threshold_px = 4.0;  //!< inlier bound on |(duL, dv, duR)| [px]
	int ransac_iterations = 200;  //!< RANSAC upper bound
	double sigma_px = 0.5;	//!< measurement noise of the solve [px]
	double sigma_disparity_px = 0;	//!< the disparity's extra noise (geometry::TPoseSolverOptions) [px]
	double huber_k = 1.0;  //!< Huber threshold [sigmas]
	bool two_view_ba = true;  //!< solve by two-view bundle adjustment (else fixed landmarks)
	/** Score the input's prediction as a RANSAC hypothesis (if it has one). */
	bool ransac_prediction = true;
	/** RANSAC's preference for hypotheses near the prediction
	 * (geometry::TRansacOptions::prior_sigma_m), 0 = off [m]. */
	double ransac_prior_sigma_m = 0.15;
	int min_inliers = 10;  //!< fewer RANSAC inliers: FewInliers; fewer re-selected: keep the first solve
};

/** Input of one estimation. */
struct TRelativePoseInput
{
	const std::vector<geometry::TStereoCorrespondence>* corr = nullptr;	 //!< reference landmarks <-> current measurements
	geometry::TStereoCalib calib;  //!< the current frame's calibration
	/** The motion prior's prediction of T_curr_ref; nullptr = solve without
	 * the prior (random minimal sets only, no preference). */
	const Eigen::Isometry3d* T_curr_ref_pred = nullptr;
	/** Scales ransac_prior_sigma_m (the VO: 1 + frames since the last tracked
	 * one, since its prediction spans them all). */
	double prior_sigma_scale = 1.0;
	uint32_t seed = 42;	 //!< RANSAC's seed: runs are repeatable
};

enum class RelativePoseStatus
{
	Ok,
	FewInliers,	 //!< RANSAC found fewer than min_inliers
	SolverFailed  //!< the robust solve diverged or was degenerate
};
std::string toString(RelativePoseStatus s);

/** Output of one estimation. */
struct TRelativePoseOutput
{
	RelativePoseStatus status = RelativePoseStatus::FewInliers;
	Eigen::Isometry3d T_curr_ref = Eigen::Isometry3d::Identity();
	/** Covariance of T_ref_curr = T_curr_ref^-1, left convention [m^2, rad^2]. */
	geometry::Matrix6d cov_T_ref_curr = geometry::Matrix6d::Zero();
	std::vector<uint8_t> inlier;  //!< per correspondence, of the final solve
	size_t ransac_inliers = 0;	//!< RANSAC's count
	size_t inliers = 0;	 //!< the final solve's (re-selected) count
	double rms_px = 0;	//!< RMS residual of the final solve [px]
	double ms_ransac = 0, ms_solve = 0;	 //!< stage times [ms]
	bool ok() const { return status == RelativePoseStatus::Ok; }
};

/** The relative-pose estimator (see the file comment). Stateless. */
class RelativePoseEstimator
{
   public:
	using TOptions = TRelativePoseOptions;
	explicit RelativePoseEstimator(const TOptions& o = TOptions());

	void estimate(const TRelativePoseInput& in, TRelativePoseOutput& out) const;

	const TOptions& options() const { return m_opts; }

   private:
	TOptions m_opts;
};

}  // namespace shadyloc::vo
