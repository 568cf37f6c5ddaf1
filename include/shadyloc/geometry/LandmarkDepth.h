/* ShadyLoc — a map landmark's depth from the survey frames that re-observed
 * it, not only from its own stereo pair.
 *
 * A keyframe's stereo pair has a 0.12 m baseline: a landmark 20 m away is 2.4
 * px of disparity, and its depth is uncertain by metres. Seen from the lane's
 * middle that hardly matters (the error lies along the viewing ray), but seen
 * from B m aside it moves the landmark's projection by about B / baseline
 * times the disparity error: half a lane aside, 15 times. The survey already
 * re-finds each landmark in the frames around its keyframe (the re-observation
 * count of the landmark selection); those frames see it from up to several
 * metres along the road, a baseline tens of times the stereo one for
 * landmarks off the optical axis. Here the landmark's disparity is the
 * result: the landmark is triangulated from the keyframe's pair and every
 * re-observation's stereo measurement, at its solved pose relative to the
 * keyframe and with that pose's covariance (robust least squares, Hartley &
 * Zisserman, 2nd ed., Section 12.4 and A6), and its disparity in the
 * keyframe is kept with its marginal sigma. Its pixel (uL, v) stays as
 * measured: the descriptor and the patch are centred there.
 */
#pragma once

#include <shadyloc/geometry/PoseSolver.h>
#include <shadyloc/geometry/StereoCamera.h>

#include <Eigen/Geometry>

#include <vector>

namespace shadyloc::geometry
{
/** One re-observation of a keyframe's landmark. */
struct TDepthObservation
{
	Eigen::Isometry3d T_obs_kf = Eigen::Isometry3d::Identity();	 //!< the observing left camera from the keyframe's
	Matrix6d cov_T_obs_kf = Matrix6d::Zero();  //!< its covariance, left convention [m^2, rad^2]
	Eigen::Vector3d z = Eigen::Vector3d::Zero();  //!< (uL, v, uR) in the observing frame [px]
};

struct TDepthRefinementOptions
{
	double sigma_px = 0.5;	//!< pixel noise of the keyframe's pair [px]
	/** Pixel noise of a re-observation [px]: its patch is refined across a
	 * change of scale, and its frame's pose comes from the same landmarks,
	 * so it is worse than the pair's (calibrated against true depth:
	 * docs/map.md, "Depth from re-observations"). */
	double reobservation_sigma_px = 0.5;
	int min_observations = 2;  //!< re-observations that must agree, else the stereo depth stays
	double huber_k = 2;	 //!< [whitened residual]
	double outlier_chi2 = 11.34;  //!< a re-observation further than this (3 dof, 99 %) is left out
	double stereo_chi2 = 10.83;	 //!< the refined disparity must agree with the pair's (1 dof, 99.9 %)
};

struct TDepthRefinement
{
	bool ok = false;  //!< false: keep the stereo pair's depth
	double disparity = 0;  //!< true disparity D = fx b / Z in the keyframe [px]
	double sigma_disparity = 0;	 //!< its standard deviation [px]
	int used = 0;  //!< re-observations that agree
};

/** The disparity of the keyframe measurement z_kf = (uL, v, uR) that best
 * explains it and its re-observations `obs`: the landmark is solved in 3-D
 * (sigma_px on the pair's pixel coordinates, reobservation_sigma_px on the
 * others', plus each re-observation's pose covariance), Huber-weighted Gauss-Newton from the pair's triangulation,
 * then once more without the re-observations beyond outlier_chi2. The
 * disparity's sigma is the marginal of that solve, scaled up by the fit's
 * chi^2 per degree of freedom where that exceeds 1. */
TDepthRefinement refineDisparity(
	const TStereoCalib& calib, const Eigen::Vector3d& z_kf, const std::vector<TDepthObservation>& obs,
	const TDepthRefinementOptions& o = {});

}  // namespace shadyloc::geometry
