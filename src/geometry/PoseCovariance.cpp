/* ShadyLoc — pose covariance along chains; conversion to MRPT. */
#include <shadyloc/geometry/PoseCovariance.h>

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose3D.h>

#include "Skew.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace shadyloc::geometry
{
Vector6d localLeft(const Eigen::Isometry3d& T, const Eigen::Isometry3d& T0)
{
	// T = (exp([phi]x) R0, exp([phi]x) t0 + rho)
	const Eigen::Matrix3d dR = T.linear() * T0.linear().transpose();
	const Eigen::AngleAxisd aa(dR);
	Vector6d xi;
	xi.tail<3>() = aa.angle() * aa.axis();
	xi.head<3>() = T.translation() - dR * T0.translation();
	return xi;
}

TPoseWithCov compose(const TPoseWithCov& ab, const TPoseWithCov& bc, Matrix6d* J_ab, Matrix6d* J_bc)
{
	// exp(xi_ab) T_ab exp(xi_bc) T_bc = exp(xi_ab) exp(Ad(T_ab) xi_bc) T_ab T_bc
	const Matrix6d A = adjoint(ab.T);
	TPoseWithCov ac;
	ac.T = ab.T * bc.T;
	ac.cov = ab.cov + A * bc.cov * A.transpose();
	ac.cov = 0.5 * (ac.cov + ac.cov.transpose());
	if (J_ab) J_ab->setIdentity();
	if (J_bc) *J_bc = A;
	return ac;
}

TPoseWithCov inverse(const TPoseWithCov& ab, Matrix6d* J)
{
	TPoseWithCov ba;
	ba.T = ab.T.inverse();
	const Matrix6d A = -adjoint(ba.T);
	ba.cov = A * ab.cov * A.transpose();
	ba.cov = 0.5 * (ba.cov + ba.cov.transpose());
	if (J) *J = A;
	return ba;
}

TPoseWithCov composeChain(const std::vector<TPoseWithCov>& links)
{
	TPoseWithCov acc;
	for (const auto& l : links) acc = compose(acc, l);
	return acc;
}

Matrix6d jacobianYPRWrtLeft(const Eigen::Isometry3d& T)
{
	const mrpt::poses::CPose3D p = mrpt::poses::CPose3D::FromHomogeneousMatrix(
		mrpt::math::CMatrixDouble44(T.matrix()));
	const double y = p.yaw(), pt = p.pitch();
	const double cy = std::cos(y), sy = std::sin(y), cp = std::cos(pt), sp = std::sin(pt);
	if (std::abs(cp) < 1e-6)
		throw std::domain_error("jacobianYPRWrtLeft: pitch at +-90 deg (gimbal lock), yaw and roll inseparable");
	// R = Rz(yaw) Ry(pitch) Rx(roll): a left rotation phi changes the angles by
	// E^-1 phi, with E's columns the axes of the three elementary rotations in
	// the outer frame: e_z, Rz e_y, Rz Ry e_x.
	Eigen::Matrix3d E;
	E << 0, -sy, cy * cp,  //
		0, cy, sy * cp,	 //
		1, 0, -sp;
	Matrix6d J = Matrix6d::Zero();
	// t' = t + rho + phi x t: dt/drho = I, dt/dphi = -[t]x.
	J.topLeftCorner<3, 3>().setIdentity();
	J.topRightCorner<3, 3>() = -skew(T.translation());
	J.bottomRightCorner<3, 3>() = E.inverse();
	return J;
}

mrpt::poses::CPose3DPDFGaussian toCPose3DPDFGaussian(const TPoseWithCov& p)
{
	const Matrix6d J = jacobianYPRWrtLeft(p.T);
	Matrix6d C = J * p.cov * J.transpose();
	C = 0.5 * (C + C.transpose());
	mrpt::poses::CPose3DPDFGaussian out;
	out.mean = mrpt::poses::CPose3D::FromHomogeneousMatrix(mrpt::math::CMatrixDouble44(p.T.matrix()));
	out.cov = mrpt::math::CMatrixDouble66(C);
	return out;
}

double mahalanobis2(const Vector6d& xi, const Matrix6d& S)
{
	if (!S.allFinite() || !xi.allFinite()) return std::numeric_limits<double>::infinity();
	const Eigen::LDLT<Matrix6d> ldlt(0.5 * (S + S.transpose()));
	if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::numeric_limits<double>::infinity();
	const double d2 = xi.dot(ldlt.solve(xi));
	return std::isfinite(d2) && d2 >= 0 ? d2 : std::numeric_limits<double>::infinity();
}

namespace
{
double largestSigma(const Eigen::Matrix3d& block)
{
	Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(block, Eigen::EigenvaluesOnly);
	return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}
}  // namespace

double translationSigma(const Matrix6d& cov) { return largestSigma(cov.topLeftCorner<3, 3>()); }
double rotationSigma(const Matrix6d& cov) { return largestSigma(cov.bottomRightCorner<3, 3>()); }

}  // namespace shadyloc::geometry
