/* ShadyLoc — relative pose of a stereo frame against a set of 3D landmarks:
 * RANSAC on 3D-3D correspondences (3-point minimal sets solved in closed form,
 * Horn 1987 / Umeyama 1991, no scale), then a robust Gauss-Newton on the stereo
 * reprojection error (uL, v, uR) with a Huber kernel, and the 6x6 covariance
 * of the result from the inverse of J^T W J.
 *
 * Pose perturbation (the convention of every covariance here): a pose T
 * (R, t) is perturbed on the left, T' = (exp([phi]x) R, exp([phi]x) t + rho),
 * xi = (rho, phi) in R^6, translation first [m, rad]. To first order this is
 * SE(3)'s left perturbation exp(xi^) T.
 */
#pragma once

#include <shadyloc/geometry/StereoCamera.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <limits>
#include <vector>

namespace shadyloc::geometry
{
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix36d = Eigen::Matrix<double, 3, 6>;

/** The left retraction above: T' = (exp([phi]x) R, exp([phi]x) t + rho). */
Eigen::Isometry3d retractLeft(const Vector6d& xi, const Eigen::Isometry3d& T);

/** Adjoint of T for xi = (rho, phi): Ad = [[R, [t]x R], [0, R]]. */
Matrix6d adjoint(const Eigen::Isometry3d& T);

/** Covariance of T^-1 given that of T (both in the left convention). */
Matrix6d invertCovariance(const Eigen::Isometry3d& T, const Matrix6d& covT);

/** One correspondence: a landmark in the reference frame and its measurement
 * in the current frame. */
struct TStereoCorrespondence
{
	Eigen::Vector3d P_ref;	//!< landmark in the reference (keyframe) left camera [m]
	Eigen::Matrix3d cov_ref = Eigen::Matrix3d::Zero();	//!< its covariance [m^2]
	/** The landmark's measurement (uL, v, uR) in the reference frame, from
	 * which P_ref was triangulated (with calib_ref) [px]; NaN = unknown. The
	 * two-view adjustment needs it. */
	Eigen::Vector3d z_ref = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
	TStereoCalib calib_ref;	 //!< the reference frame's calibration (of z_ref)
	/** Standard deviation of z_ref's true disparity where other views refined
	 * it [px] (TStereoCalib::measurementCovariance); 0 = sigma_px on each of
	 * uL, v, uR as measured by the pair. */
	double sigma_disparity_ref = 0;
	Eigen::Vector3d z_curr;	 //!< measurement (uL, v, uR) in the current frame [px]
	Eigen::Vector3d P_curr;	 //!< triangulation of z_curr in the current frame [m]

	bool hasReferenceObservation() const { return z_ref.allFinite(); }
};

/** Residual r = project(T_curr_ref * P_ref) - z and J = dr/dxi (3x6) for the
 * left perturbation of T_curr_ref. False if the point is behind the camera. */
bool stereoResidual(
	const TStereoCalib& calib, const Eigen::Isometry3d& T_curr_ref, const Eigen::Vector3d& P_ref,
	const Eigen::Vector3d& z, Eigen::Vector3d& r, Matrix36d* J = nullptr);

/** Closed-form rigid transform T with dst_i ~ T src_i (least squares, no
 * scale). False if fewer than 3 points or (near) collinear. */
bool rigidTransform3D(
	const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
	Eigen::Isometry3d& T);

struct TRansacOptions
{
	int max_iterations = 200;  //!< upper bound on hypotheses
	double confidence = 0.999;	//!< stop when this probability of an all-inlier set is reached
	double inlier_threshold_px = 2.0;  //!< max |r| (norm of (duL, dv, duR)) of an inlier [px]
	uint32_t seed = 42;	 //!< fixed seed: runs are repeatable
	/** Hypotheses of T_curr_ref scored (and locally optimised) before the
	 * random minimal sets, e.g. the motion model's prediction. */
	std::vector<Eigen::Isometry3d> hypotheses;
	/** With a first hypothesis (a motion prediction) and sigma > 0, a
	 * hypothesis scores its inliers less 0.5 (|t - t_pred| / sigma)^2, t its
	 * translation: between consensus sets of similar size the one nearer the
	 * prediction wins (a repetitive structure matched one period off forms
	 * a consistent wrong set); 0 = inliers only [m]. */
	double prior_sigma_m = 0;
	/** Local optimisation by two-view bundle adjustment (else with fixed landmarks). */
	bool two_view_ba = false;
};

struct TRansacResult
{
	bool ok = false;
	Eigen::Isometry3d T_curr_ref = Eigen::Isometry3d::Identity();
	std::vector<uint8_t> inlier;  //!< one flag per correspondence
	int inliers = 0;
	int iterations = 0;
};

/** 3-point RANSAC; the hypothesis with most inliers is refitted on all its
 * inliers (3D-3D) before the final inlier count. */
TRansacResult ransacStereoPose(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const TRansacOptions& o);

struct TPoseSolverOptions
{
	int max_iterations = 15;  //!< Gauss-Newton iterations
	double sigma_px = 0.5;	//!< measurement noise per pixel coordinate [px]
	/** Noise of the disparity beyond sigma_px: uR = uL - d, and a channel
	 * whose stereo matching is poorer (the invariant image) measures d worse
	 * than it places a corner; it adds to uR's variance only [px]. */
	double sigma_disparity_px = 0;
	double huber_k = 2.0;  //!< Huber threshold on the whitened residual norm [sigmas]
	double convergence = 1e-7;	//!< stop when |dxi| falls below this
	bool use_landmark_covariance = true;  //!< add the projected cov_ref to each residual's covariance
	/** False where only the pose is used (RANSAC's local optimisation, the
	 * bootstrap's resamples): the final linearisation, the covariance and
	 * rms_px are skipped, and a solve whose steps stayed finite is ok. */
	bool covariance = true;
};

/** Variances of one stereo measurement's (uL, v, uR), independent: sigma_px
 * on each, and sigma_disparity_px more on uR [px^2]. */
Eigen::Vector3d measurementVariances(const TPoseSolverOptions& o);

struct TPoseSolution
{
	bool ok = false;
	Eigen::Isometry3d T_curr_ref = Eigen::Isometry3d::Identity();
	/** Covariance of T_ref_curr (= T_curr_ref^-1), left convention [m^2, rad^2]. */
	Matrix6d cov_T_ref_curr = Matrix6d::Identity();
	int iterations = 0;
	double rms_px = 0;	//!< RMS reprojection residual over the used correspondences [px]
};

/** Robust Gauss-Newton from T_init over the correspondences with use[i] != 0
 * (all if use is empty). The reference landmarks are fixed; their covariance
 * enters each residual's covariance (use_landmark_covariance). */
TPoseSolution solveStereoPose(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c,
	const std::vector<uint8_t>& use, const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o);

/** One correspondence's robust normal-equation terms at a pose: J^T W J,
 * J^T W r (W the residual's inverse covariance times the Huber weight) and
 * |r|^2 [px^2]; ok is false when the landmark does not project. */
struct TNormalTerms
{
	Matrix6d H = Matrix6d::Zero();
	Vector6d g = Vector6d::Zero();
	double sq = 0;
	bool ok = false;
};

/** The terms of every correspondence at T. */
std::vector<TNormalTerms> normalTermsAt(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const Eigen::Isometry3d& T,
	const TPoseSolverOptions& o);

/** solveStereoPose over c[i] taken count[i] times (a bootstrap resample
 * drawn with replacement). atInit, when given, holds normalTermsAt(T_init):
 * resamples that all start at one pose share their first linearisation. */
TPoseSolution solveStereoPoseCounted(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const std::vector<int>& count,
	const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o, const std::vector<TNormalTerms>* atInit = nullptr);

/** One correspondence linearised at a pose for the chord iteration: J^T W
 * and J^T W J without the Huber weight, and W (the residual's inverse
 * covariance); ok is false when the landmark does not project. */
struct TFrozenTerms
{
	Eigen::Matrix<double, 6, 3> JtW = Eigen::Matrix<double, 6, 3>::Zero();
	Matrix6d JtWJ = Matrix6d::Zero();
	Eigen::Matrix3d W = Eigen::Matrix3d::Zero();
	bool ok = false;
};

/** The frozen terms of every correspondence at T. */
std::vector<TFrozenTerms> frozenTermsAt(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const Eigen::Isometry3d& T,
	const TPoseSolverOptions& o);

/** solveStereoPoseCounted by the chord method (a simplified Gauss-Newton):
 * every step re-evaluates each residual and its Huber weight at the
 * iterate, but keeps the Jacobian and covariance of `at` (frozenTermsAt
 * T_init). A resample's pose moves from T_init by about its own sigma, so
 * the frozen Jacobians differ from the iterate's by that share of the
 * landmark's depth: the fixed point is the same to first order, at about a
 * quarter of the arithmetic per term (no Jacobian, no 3x3 covariance
 * propagated and inverted). Needs o.covariance false. */
TPoseSolution solveStereoPoseCountedChord(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const std::vector<int>& count,
	const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o, const std::vector<TFrozenTerms>& at);


/** Two-view bundle adjustment from T_init: the pose and every used landmark
 * are unknowns; each landmark has its stereo measurement z_ref in the
 * reference frame (projected with calib_ref) and z_curr in the current frame
 * (with calib), both with sigma_px noise and a Huber kernel.
 * Landmarks are eliminated by the Schur complement; Levenberg-Marquardt
 * steps are accepted only when the cost decreases. cov_T_ref_curr is the
 * inverse of the pose's marginal information. cov_ref and
 * use_landmark_covariance are not used (the landmarks are estimated).
 * Throws std::invalid_argument if a used correspondence has no z_ref. */
TPoseSolution solveStereoPoseTwoView(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c,
	const std::vector<uint8_t>& use, const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o);

}  // namespace shadyloc::geometry
