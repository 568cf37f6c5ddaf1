/* ShadyLoc — rectified stereo camera model. */
#include <shadyloc/geometry/StereoCamera.h>

#include <mrpt/obs/CObservationStereoImages.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace shadyloc::geometry
{
Eigen::Vector3d TStereoCalib::project(const Eigen::Vector3d& P, Eigen::Matrix3d* J) const
{
	const double iz = 1.0 / P.z();
	const Eigen::Vector3d z(
		fx * P.x() * iz + cx, fy * P.y() * iz + cy, fx * (P.x() - baseline) * iz + cxR);
	if (J)
	{
		const double iz2 = iz * iz;
		*J << fx * iz, 0, -fx * P.x() * iz2,	//
			0, fy * iz, -fy * P.y() * iz2,	//
			fx * iz, 0, -fx * (P.x() - baseline) * iz2;
	}
	return z;
}

bool TStereoCalib::triangulate(double uL, double v, double uR, Eigen::Vector3d& P, Eigen::Matrix3d* J) const
{
	const double D = disparity(uL, uR);
	if (!(D > 1e-6)) return false;
	const double Z = fx * baseline / D;
	const double X = (uL - cx) * baseline / D;
	const double Y = (v - cy) * Z / fy;
	P = Eigen::Vector3d(X, Y, Z);
	if (J)
	{
		// dD/duL = 1, dD/duR = -1; Z = fx b / D, X = (uL-cx) b / D, Y = (v-cy) Z / fy.
		*J << baseline / D - X / D, 0, X / D,  //
			-Y / D, Z / fy, Y / D,	//
			-Z / D, 0, Z / D;
	}
	return true;
}

Eigen::Matrix3d TStereoCalib::triangulationCovariance(const Eigen::Matrix3d& J, double sigma_px) const
{
	return (sigma_px * sigma_px) * (J * J.transpose());
}

Eigen::Matrix3d TStereoCalib::measurementCovariance(double sigma_px, double sigma_disparity_px)
{
	const double s2 = sigma_px * sigma_px;
	if (!(sigma_disparity_px > 0)) return s2 * Eigen::Matrix3d::Identity();
	// uR = uL + doffs - D with uL, v, D independent.
	Eigen::Matrix3d C;
	C << s2, 0, s2,	 //
		0, s2, 0,  //
		s2, 0, s2 + sigma_disparity_px * sigma_disparity_px;
	return C;
}

Eigen::Matrix3d TStereoCalib::triangulationCovariance(
	const Eigen::Matrix3d& J, double sigma_px, double sigma_disparity_px) const
{
	if (!(sigma_disparity_px > 0)) return triangulationCovariance(J, sigma_px);
	return J * measurementCovariance(sigma_px, sigma_disparity_px) * J.transpose();
}

TStereoCalib TStereoCalib::FromObservation(const mrpt::obs::CObservationStereoImages& obs)
{
	const auto& L = obs.leftCamera;
	const auto& R = obs.rightCamera;
	const auto& T = obs.rightCameraPose;  // right camera in the left camera frame
	const double ty = T.y(), tz = T.z();
	const auto q = T.quat();
	const double rotDev = std::abs(std::abs(q.r()) - 1.0);
	if (rotDev > 1e-6 || std::abs(ty) > 1e-6 || std::abs(tz) > 1e-6 || !(T.x() > 0))
		throw std::invalid_argument(
			"stereo observation '" + obs.sensorLabel +
			"': not a rectified pair (right camera must be translated along +x only)");
	if (std::abs(L.fx() - R.fx()) > 1e-3 || std::abs(L.fy() - R.fy()) > 1e-3 ||
		std::abs(L.cy() - R.cy()) > 1e-3)
		throw std::invalid_argument(
			"stereo observation '" + obs.sensorLabel +
			"': left and right focal lengths / cy differ (not rectified)");
	TStereoCalib c;
	c.fx = L.fx();
	c.fy = L.fy();
	c.cx = L.cx();
	c.cy = L.cy();
	c.cxR = R.cx();
	c.baseline = T.x();
	return c;
}

TStereoCalib TStereoCalib::scaled(double s) const
{
	TStereoCalib c = *this;
	c.fx *= s;
	c.fy *= s;
	// pixel centres: u' = (u + 0.5) s - 0.5
	c.cx = (cx + 0.5) * s - 0.5;
	c.cy = (cy + 0.5) * s - 0.5;
	c.cxR = (cxR + 0.5) * s - 0.5;
	return c;
}

std::string TStereoCalib::asString() const
{
	std::ostringstream o;
	o << "fx=" << fx << " fy=" << fy << " cx=" << cx << " cy=" << cy << " cxR=" << cxR
	  << " baseline=" << baseline << "m";
	return o.str();
}

}  // namespace shadyloc::geometry
