/* ShadyLoc — a tiny ray caster for VO tests and benchmarks: a straight
 * corridor (two walls, floor, ceiling, an end wall) covered with a two-scale
 * random colour checker, seen by a rectified pinhole stereo pair at known
 * poses. Colour texture (not just grey) so that both the monochrome and the
 * illumination-invariant channels have something to track. Not a simulator
 * of light: no shading, no shadows.
 */
#pragma once

#include <shadyloc/geometry/StereoCamera.h>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <cstdint>

namespace shadyloc::sim
{
struct TCorridorOptions
{
	int width = 320, height = 240;	//!< image size [px]
	double fx = 250;  //!< focal length [px] (fy = fx, principal point at the centre)
	double baseline = 0.2;	//!< stereo baseline [m]
	double half_width = 2.0;  //!< walls at x = +-half_width [m]
	double half_height = 1.5;  //!< ceiling and floor at y = -+half_height [m]
	double length = 60.0;  //!< end wall at z = length [m]
	double coarse_cell = 0.45;	//!< texture cell sizes [m]
	double fine_cell = 0.11;
	int supersample = 2;  //!< rays per pixel per axis (anti-aliasing)
	double noise_sigma = 1.0;  //!< additive Gaussian pixel noise [grey levels], 0 = none
	uint32_t seed = 1;	//!< texture seed
};

class SyntheticCorridor
{
   public:
	explicit SyntheticCorridor(const TCorridorOptions& o = {});
	geometry::TStereoCalib calib() const;
	const TCorridorOptions& options() const { return m_o; }

	/** Renders both eyes (CV_8UC3, BGR) with the left camera at T_world_left
	 * (x right, y down, z forward; the corridor runs along world +z).
	 * noiseSeed varies the pixel noise between frames. */
	void render(const Eigen::Isometry3d& T_world_left, cv::Mat& leftBGR, cv::Mat& rightBGR, uint32_t noiseSeed = 0) const;

	/** Depth Z [m] (along the camera's optical axis) of the surface seen
	 * through pixel (u, v) of a camera at T_world_cam; 0 if nothing is hit. */
	double depth(const Eigen::Isometry3d& T_world_cam, double u, double v) const;

	/** A smooth example path: forward `speed` m per frame, sway and yaw/pitch wobble. */
	static Eigen::Isometry3d examplePose(int frame, double speed = 0.1);

   private:
	void renderEye(const Eigen::Isometry3d& T_world_cam, cv::Mat& out, uint32_t noiseSeed) const;
	Eigen::Vector3d shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const;
	/** Ray parameter of the first hit (inf if none) and the plane index. */
	double intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, int& plane) const;
	TCorridorOptions m_o;
};

}  // namespace shadyloc::sim
