/* ShadyLoc — the rectified stereo camera model: projection of a point in the
 * left camera frame to a stereo measurement (uL, v, uR), triangulation back,
 * and the Jacobians of both (for covariance propagation and Gauss-Newton).
 *
 * Frames: left camera, x right, y down, z forward (metres). Pixels: u right,
 * v down. The two principal points may differ along x (Middlebury's `doffs`):
 *     uL = fx X/Z + cx,   v = fy Y/Z + cy,   uR = fx (X - b)/Z + cxR
 * so the measured difference uL - uR = fx b/Z - doffs with doffs = cxR - cx,
 * and the true (depth) disparity is D = uL - uR + doffs = fx b / Z.
 */
#pragma once

#include <Eigen/Core>

#include <string>

namespace mrpt::obs
{
class CObservationStereoImages;
}

namespace shadyloc::geometry
{
/** Intrinsics of a rectified pair (both eyes share fx, fy, cy). */
struct TStereoCalib
{
	double fx = 500, fy = 500;	//!< focal lengths [px]
	double cx = 320, cy = 240;	//!< left principal point [px]
	double cxR = 320;  //!< right principal point x [px] (differs from cx when doffs != 0)
	double baseline = 0.12;	 //!< distance between the optical centres [m]

	/** cxR - cx [px]: Middlebury's doffs. */
	double doffs() const { return cxR - cx; }
	/** True disparity D = fx b / Z [px] of a measurement pair. */
	double disparity(double uL, double uR) const { return uL - uR + doffs(); }

	/** (uL, v, uR) of P; J (if given) = d(uL,v,uR)/dP. Requires P.z() > 0. */
	Eigen::Vector3d project(const Eigen::Vector3d& P, Eigen::Matrix3d* J = nullptr) const;

	/** P from (uL, v, uR); J (if given) = dP/d(uL,v,uR). False if the true
	 * disparity is not positive (point at or behind infinity). */
	bool triangulate(double uL, double v, double uR, Eigen::Vector3d& P, Eigen::Matrix3d* J = nullptr) const;

	/** Covariance of a triangulated point, from isotropic pixel noise
	 * sigma_px on each of uL, v, uR: J diag(s^2) J^T. */
	Eigen::Matrix3d triangulationCovariance(const Eigen::Matrix3d& J, double sigma_px) const;

	/** Covariance of a point whose disparity was measured apart from its
	 * pixel (a depth refined by other views, LandmarkDepth.h): uL and v with
	 * noise sigma_px, the true disparity D with sigma_disparity_px, so uR =
	 * uL + doffs - D. sigma_disparity_px <= 0 gives the isotropic form above. */
	Eigen::Matrix3d triangulationCovariance(const Eigen::Matrix3d& J, double sigma_px, double sigma_disparity_px) const;

	/** Covariance of a stereo measurement (uL, v, uR) under that model. */
	static Eigen::Matrix3d measurementCovariance(double sigma_px, double sigma_disparity_px);

	/** From a rectified MRPT stereo observation: left K, right cx, baseline =
	 * |rightCameraPose.x|. Throws if the right camera is rotated or offset
	 * other than along x (not rectified), naming the sensor. */
	static TStereoCalib FromObservation(const mrpt::obs::CObservationStereoImages& obs);

	/** Scales the intrinsics (image resized by factor s). */
	TStereoCalib scaled(double s) const;

	std::string asString() const;
};

}  // namespace shadyloc::geometry
