/* ShadyLoc — the surface normal at each stereo measurement, for patches that
 * follow the viewpoint (PatchWarp.h). A dense disparity image (OpenCV's
 * semi-global matcher, Hirschmueller, "Stereo Processing by Semiglobal
 * Matching and Mutual Information", PAMI 2008) gives the disparity around a
 * measurement; a plane d = c + a du + b dv fitted to it by least squares
 * (one pass dropping outliers) is the image of a 3D plane n^T X = rho:
 *   a = B n_x / rho,  b = B n_y fx / (fy rho),  c = fx B (n^T x) / rho
 * with x = ((u - cx) / fx, (v - cy) / fy, 1), so
 *   n ~ (a fx, b fy, c - a (u - cx) - b (v - cy)).
 * The disparity image is made once per frame, from the channel with the
 * best-conditioned images; the geometry it measures is every channel's.
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/geometry/StereoCamera.h>

#include <opencv2/core/mat.hpp>

#include <vector>

namespace shadyloc::features
{
/** Options of the normal estimation ([map] normal_* keys). */
struct TSurfaceNormalOptions
{
	int window_radius_px = 8;  //!< the plane is fitted to the (2r+1)^2 disparities around the measurement [px]
	/** Fewer valid disparities than this share of the window leave the
	 * normal unknown (textureless or occluded surroundings). */
	double min_valid_fraction = 0.5;
	/** Disparities this far from the fitted plane are dropped before the
	 * second fit (another surface in the window) [px]. */
	double outlier_px = 1.0;
	/** The fitted plane must pass within this of the measurement's own
	 * disparity, or the window saw another surface [px]. */
	double max_centre_error_px = 1.0;
	int max_disparity_px = 96;	//!< searched by the dense matcher (rounded up to 16) [px]
	int block_size_px = 5;	//!< the dense matcher's block [px], odd
};

/** Dense disparity (CV_32F, NaN where the matcher found none) of a rectified
 * CV_8UC1 pair, as uL - uR. Deterministic for a given pair. */
cv::Mat denseDisparity(const cv::Mat& left8, const cv::Mat& right8, const TSurfaceNormalOptions& o);

/** Sets `normal` (unit, in the left camera, facing the camera: n^T P < 0)
 * of every measurement from `disparity`, or zero where the fit fails;
 * returns the number of normals found. */
size_t estimateNormals(
	const cv::Mat& disparity, const geometry::TStereoCalib& calib, const TSurfaceNormalOptions& o,
	std::vector<TStereoMeasurement>& meas);

}  // namespace shadyloc::features
