/* ShadyLoc — patches that follow the viewpoint. A small patch of a surface
 * around a landmark is nearly planar; seen from a keyframe and from another
 * camera, its two images are related by the homography that plane induces,
 * H = K' (R + t n^T / rho) K^-1 for the plane n^T X = rho in the keyframe's
 * camera (Hartley & Zisserman, "Multiple View Geometry", 2nd ed., Section
 * 13.1). Near the landmark that map is affine: its Jacobian A maps keyframe
 * pixel offsets to live pixel offsets. The keyframe's BRIEF tests and pixel
 * patch are compared with the live image resampled through A instead of
 * as it is (locally planar patch features: Molton, Davison & Reid, BMVC 2004).
 *
 * A half-lane offset shears the road surface by about offset / camera height
 * (1.75 m / 1.5 m: more than the BRIEF patch is wide) and scales a facade
 * along the road by its distance ratio; unwarped, neither matches
 * (docs/localisation.md, "Patches that follow the viewpoint").
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/geometry/StereoCamera.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <array>
#include <cstdint>

namespace shadyloc::features
{
/** The Jacobian at the landmark's keyframe pixel of the map from keyframe
 * pixels (calibKf) to pixels of a camera at T_curr_kf (calib), induced by the
 * plane through P_kf with unit normal n_kf (both in the keyframe's left
 * camera). False when the landmark or the plane is behind either camera, or
 * the plane is seen nearly edge-on (A's singular values outside
 * [1/max_stretch, max_stretch]): no patch of it would match. */
bool planeInducedAffine(
	const geometry::TStereoCalib& calibKf, const geometry::TStereoCalib& calib, const Eigen::Isometry3d& T_curr_kf,
	const Eigen::Vector3d& P_kf, const Eigen::Vector3d& n_kf, Eigen::Matrix2d& A, double max_stretch = 4.0);

/** How far A is from the identity: the largest |A_ij - I_ij|. */
double warpDistortion(const Eigen::Matrix2d& A);

/** A BRIEF test pattern mapped through A: each keyframe offset d becomes the
 * live offset round(A d), so a descriptor of the live (smoothed) image made
 * with it compares with the keyframe's. Integer offsets keep the cost of an
 * unwarped descriptor (the image is smoothed with sigma 2 first, so half a
 * pixel of rounding changes few tests). */
class WarpedBriefPattern
{
   public:
	WarpedBriefPattern(const BriefExtractor& brief, const Eigen::Matrix2d& A);
	/** The descriptor at integer (x, y) of a smoothed CV_8UC1 image; false when
	 * a test falls outside the image. */
	bool compute(const cv::Mat& smoothed8, int x, int y, TBriefDescriptor& d) const;

   private:
	std::array<std::array<int16_t, 4>, 256> m_pattern{};
	int m_reach = 0;  //!< the largest |offset| of any test [px]
};

/** locatePatch (StereoFeatures.h) for a keyframe patch seen through A: the
 * live image around the integer pixel (x0, y0) is resampled into the
 * keyframe's pixel grid (bilinear), the patch located there, and the result
 * mapped back: (x, y) = (x0, y0) + A (keyframe offset). A = I gives
 * locatePatch's answer. */
bool locateWarpedPatch(
	const std::array<uint8_t, kPatchSize * kPatchSize>& patch, const cv::Mat& img, int x0, int y0,
	const Eigen::Matrix2d& A, int radius_px, float min_zncc, int iterations, float& x, float& y);

}  // namespace shadyloc::features
