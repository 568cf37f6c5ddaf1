/* ShadyLoc — first-order propagation of pose covariances along a chain of
 * relative poses (keyframe links, VO steps), and their conversion to MRPT's
 * CPose3DPDFGaussian.
 *
 * Convention (geometry/PoseSolver.h): a pose T = (R, t) is perturbed on the
 * left, T' = (exp([phi]x) R, exp([phi]x) t + rho), xi = (rho, phi),
 * translation first [m, rad]; Cov(T) = E[xi xi^T].
 *   compose:  T_a_c = T_a_b T_b_c,  xi_ac = xi_ab + Ad(T_a_b) xi_bc
 *   inverse:  T_b_a = T_a_b^-1,     xi_ba = -Ad(T_a_b^-1) xi_ab
 * (first order; Barfoot & Furgale, "Associating Uncertainty With
 * Three-Dimensional Poses for Use in Estimation Problems", IEEE T-RO 2014).
 * MRPT's CPose3DPDFGaussian holds (x, y, z, yaw, pitch, roll) with
 * R = Rz(yaw) Ry(pitch) Rx(roll); its covariance is J Cov(T) J^T with J the
 * Jacobian of those six numbers with respect to xi.
 */
#pragma once

#include <shadyloc/geometry/PoseSolver.h>

#include <mrpt/poses/CPose3DPDFGaussian.h>

#include <vector>

namespace shadyloc::geometry
{
/** A pose and its covariance (left convention above). */
struct TPoseWithCov
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	Matrix6d cov = Matrix6d::Zero();  //!< [m^2, m rad, rad^2]
};

/** The inverse of retractLeft: xi with retractLeft(xi, T0) = T (rotation
 * angle below pi). */
Vector6d localLeft(const Eigen::Isometry3d& T, const Eigen::Isometry3d& T0);

/** T_a_c = T_a_b T_b_c with Cov = J_ab C_ab J_ab^T + J_bc C_bc J_bc^T (the two
 * independent); J_ab = I, J_bc = Ad(T_a_b), returned if asked for. */
TPoseWithCov compose(const TPoseWithCov& ab, const TPoseWithCov& bc, Matrix6d* J_ab = nullptr, Matrix6d* J_bc = nullptr);

/** T_b_a = T_a_b^-1 with Cov = J C J^T, J = -Ad(T_a_b^-1). */
TPoseWithCov inverse(const TPoseWithCov& ab, Matrix6d* J = nullptr);

/** T_0_n = T_0_1 T_1_2 ... T_{n-1}_n, links independent (e.g. a keyframe
 * chain's T_prevkf_kf with their covariances); identity for an empty chain. */
TPoseWithCov composeChain(const std::vector<TPoseWithCov>& links);

/** d(x, y, z, yaw, pitch, roll) / d xi at T (MRPT's Euler angles). Throws
 * std::domain_error near pitch = +-90 deg (gimbal lock: yaw and roll are
 * not separable there). */
Matrix6d jacobianYPRWrtLeft(const Eigen::Isometry3d& T);

/** T and its covariance as MRPT's CPose3DPDFGaussian (mean T, covariance
 * J cov J^T with J = jacobianYPRWrtLeft(T)). */
mrpt::poses::CPose3DPDFGaussian toCPose3DPDFGaussian(const TPoseWithCov& p);

/** Mahalanobis distance^2 xi^T S^-1 xi; infinity if S is not finite and
 * positive definite (e.g. poses in frames nothing relates). */
double mahalanobis2(const Vector6d& xi, const Matrix6d& S);

/** The largest standard deviation of a pose covariance's translation [m]. */
double translationSigma(const Matrix6d& cov);
/** ... and of its rotation [rad]. */
double rotationSigma(const Matrix6d& cov);

}  // namespace shadyloc::geometry
