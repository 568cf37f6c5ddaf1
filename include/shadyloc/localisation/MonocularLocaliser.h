/* ShadyLoc — the localiser's core for a single image (2D-3D): one image of
 * a live channel against a stereo keyframe of the dual-channel map, with the
 * live camera's own intrinsics. For monocular live cameras, and for the
 * Middlebury check (a map of a stereo pair localises a relit image of one
 * eye alone; docs/localisation.md, "Single image against a stereo keyframe").
 *
 *   1. features of the image made exactly as the stereo extractor makes its
 *      left-image features (same pre-smoothing, FAST grid, borders, BRIEF
 *      pattern and patch), so they compare with the map's descriptors; no
 *      stereo partner is needed;
 *   2. matching: each map landmark (its BRIEF, its 3D point with covariance)
 *      against the image's features: all of them (no prior; a ratio test and
 *      a mutual check) or, with a predicted pose, those inside the
 *      chi-square gate of the landmark's predicted pixel (2 dof: the
 *      landmark's and the prediction's covariance and the pixel noise
 *      propagated to first order, with a floor; a gate longer than the
 *      ceiling is not searched and too many of them make the localiser lost,
 *      as in StereoLocaliser); the keyframe's stored patch is then located
 *      to sub-pixel in the image (ZNCC climb, parabola, Gauss-Newton with
 *      gain and offset: features::refinePatch2D);
 *   3. PnP RANSAC (OpenCV's solvePnPRansac, AP3P minimal sets) for an
 *      initial T_live_kf and its inliers;
 *   4. a robust Gauss-Newton on the reprojection error (u, v) with a Huber
 *      kernel, each residual's covariance being the pixel noise plus the
 *      landmark's covariance projected into the image; the covariance of
 *      T_kf_live from the inverse of the information at the solution;
 *      inliers re-selected at the refined pose and solved once more;
 *   5. the fix is rejected with too few inliers or a standard deviation
 *      above the bounds (as StereoLocaliser's uncertain).
 * The map refuses the live channel only when its descriptor-defining
 * parameters differ (CKeyframeMap::checkCompatible); the image size and
 * intrinsics may differ from the map's camera (they enter only through the
 * projection).
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/Channel.h>
#include <shadyloc/geometry/PoseSolver.h>
#include <shadyloc/localisation/StereoLocaliser.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <mrpt/config/CConfigFileBase.h>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace mrpt::img
{
class TCamera;
}
namespace mrpt::obs
{
class CObservationImage;
}

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::localisation
{
/** A pinhole camera without distortion (rectified or undistorted images):
 * the live monocular camera. Frames as everywhere: x right, y down, z forward. */
struct TPinholeCalib
{
	double fx = 500, fy = 500;	//!< focal lengths [px]
	double cx = 320, cy = 240;	//!< principal point [px]

	/** The left eye of a rectified stereo camera. */
	static TPinholeCalib LeftOf(const geometry::TStereoCalib& c);
	/** The right eye (its own principal point cxR). */
	static TPinholeCalib RightOf(const geometry::TStereoCalib& c);
	/** From MRPT's camera model; throws std::invalid_argument if it has
	 * distortion (undistort the image first) or non-positive focal lengths. */
	static TPinholeCalib FromCamera(const mrpt::img::TCamera& cam);

	/** (u, v) of P (P.z() > 0); J (if given) = d(u,v)/dP. */
	Eigen::Vector2d project(const Eigen::Vector3d& P, Eigen::Matrix<double, 2, 3>* J = nullptr) const;
	std::string asString() const;
};

/** One feature of a single image. */
struct TImageFeature
{
	float u = 0, v = 0;	 //!< FAST corner (integer pixel) [px]
	float response = 0;	 //!< FAST score
	features::TBriefDescriptor desc;
};

/** The features of a single image. */
struct TImageFeatures
{
	std::vector<TImageFeature> feats;
	cv::Mat image;	//!< the (pre-smoothed) grey image the keyframe patches are located in
};

/** Features of one CV_8UC1 image made as features::StereoFeatureExtractor
 * makes its left-image features with the options `fo` (pre-smoothing, FAST
 * threshold, grid, borders, BRIEF patch and seed), keeping `perCell`
 * strongest corners per bucket (not only those with a stereo partner).
 * Throws std::invalid_argument on an empty or non-CV_8UC1 image. */
void extractImageFeatures(
	const cv::Mat& grey8, const features::TStereoFeatureOptions& fo, int perCell, TImageFeatures& out);

/** Options of the 2D-3D localiser ([localiser_2d], then the keys of
 * [localiser_2d.<channel>] override). */
struct TMonocularLocaliserOptions
{
	int corners_per_cell = 60;	//!< FAST corners kept per grid bucket of the image
	// ---- matching
	int max_hamming = 80;  //!< largest BRIEF distance of a match [bits of 256]
	/** Best < ratio * second best distance among the candidates; stricter
	 * than the gated stereo search's (0.9) since without a prior every
	 * feature of the image is a candidate [-]. */
	double match_ratio = 0.8;
	bool mutual = true;	 //!< no prior: the feature's best landmark must be the landmark too
	double gate_chi2 = 9.21;  //!< with a prior: gate on (u, v), 99 % of chi^2 with 2 dof
	double gate_min_px = 3.0;  //!< every gate axis at least this long [px]
	double gate_max_px = 60.0;	//!< a longer gate is not searched (never clipped) [px]
	double max_overflow_fraction = 0.5;	 //!< more overflowing gates than this share: lost
	double refine_min_zncc = 0.6;  //!< the located keyframe patch must correlate this well
	int refine_radius_px = 2;  //!< the ZNCC climb goes at most this far from the corner [px]
	int refine_iterations = 5;	//!< Gauss-Newton steps of features::refinePatch2D
	// ---- solve
	double ransac_threshold_px = 2.0;  //!< PnP RANSAC inlier bound on the reprojection error [px]
	int ransac_iterations = 1000;  //!< upper bound on PnP RANSAC hypotheses
	double ransac_confidence = 0.999;  //!< PnP RANSAC stops at this probability of an all-inlier set
	double sigma_px = 0.5;	//!< pixel noise of (u, v) [px]
	double huber_k = 1.0;  //!< Huber threshold on the whitened residual norm [sigmas]
	int max_iterations = 20;  //!< Gauss-Newton iterations of the refinement
	/** The solver's covariance is scaled by this (correlated errors, model
	 * error; as StereoLocaliser's cov_scale) [-]. */
	double cov_scale = 4.0;
	int min_matches = 12;  //!< fewer refined matches: few_matches
	int min_inliers = 15;  //!< fewer inliers: few_inliers
	double max_sigma_m = 0.25;	//!< larger translational standard deviation: uncertain [m]
	double max_sigma_deg = 1.0;	 //!< larger rotational one: uncertain [deg]

	/** Reads `section` through core::SettingsSection; unknown keys are errors. */
	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void load(const mrpt::config::CConfigFileBase& c, const std::string& section);
	void dump(std::ostream& out) const;
	void validate() const;	//!< throws std::invalid_argument naming the option
};

/** Options for `channel`: [section], then [section.<channel>]. */
TMonocularLocaliserOptions monocularLocaliserOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& section = "localiser_2d");

/** The result of one image against one keyframe. */
struct TMonocularLocaliserResult
{
	std::string channel;
	LocaliserStatus status = LocaliserStatus::NoKeyframe;
	bool solved = false;  //!< a pose was solved (T_kf_live, cov meaningful)
	bool accepted() const { return status == LocaliserStatus::Ok; }
	uint32_t kf_id = 0;
	Eigen::Isometry3d T_kf_live = Eigen::Isometry3d::Identity();  //!< live camera in the keyframe's left camera [m]
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();  //!< of T_kf_live, left perturbation, scaled [m^2, rad^2]
	int features = 0;  //!< features of the image
	int descriptor_matches = 0;	 //!< BRIEF matches
	int matches = 0;  //!< after sub-pixel refinement
	int ransac_inliers = 0;	 //!< of PnP RANSAC
	int inliers = 0;  //!< of the refined solve
	double rms_px = 0;	//!< RMS reprojection error of the inliers [px]
	double sigma_m = -1, sigma_deg = -1;  //!< largest standard deviation (scaled) [m], [deg]
	vo::TGateStats gate;  //!< with a prior only
	double ms = 0;	//!< time [ms]
};

class MonocularLocaliser
{
   public:
	/** `channel` and `fo` are the live run's channel and feature options:
	 * the map must have a channel of that label made with the same
	 * descriptor-defining parameters (throws std::runtime_error naming both
	 * sets, or std::out_of_range naming the map's channels). The map must
	 * outlive the localiser. */
	MonocularLocaliser(
		const CKeyframeMap& map, const filters::TChannel& channel, const features::TStereoFeatureOptions& fo,
		const TMonocularLocaliserOptions& o = {});

	/** The channel's image from a live image (colour BGR, or grey for a
	 * channel that takes grey), then its features. */
	TImageFeatures features(const cv::Mat& image) const;

	/** The image's features against keyframe `kf` (throws
	 * std::out_of_range naming it if the map has none such), with the live
	 * camera `calib`; with a prediction (its kf must be `kf`), the gated
	 * search around it. Const: one instance may serve several threads. */
	TMonocularLocaliserResult localise(
		const TImageFeatures& f, const TPinholeCalib& calib, uint32_t kf,
		const std::optional<TKeyframePose>& prediction = std::nullopt) const;
	/** The same from a live image. */
	TMonocularLocaliserResult localise(
		const cv::Mat& image, const TPinholeCalib& calib, uint32_t kf,
		const std::optional<TKeyframePose>& prediction = std::nullopt) const;
	/** The same from an MRPT monocular observation (its image loaded and
	 * undistorted, its cameraParams the intrinsics). */
	TMonocularLocaliserResult localise(
		const mrpt::obs::CObservationImage& obs, uint32_t kf,
		const std::optional<TKeyframePose>& prediction = std::nullopt) const;

	const std::string& channel() const { return m_channel.label; }
	const TMonocularLocaliserOptions& options() const { return m_opts; }

   private:
	const CKeyframeMap& m_map;
	filters::TChannel m_channel;
	features::TStereoFeatureOptions m_fo;
	TMonocularLocaliserOptions m_opts;
};

/** A 2D-3D correspondence: a landmark in the reference frame and its pixel
 * in the current image. */
struct TImageCorrespondence
{
	Eigen::Vector3d P_ref;	//!< landmark in the reference (keyframe) left camera [m]
	Eigen::Matrix3d cov_ref = Eigen::Matrix3d::Zero();	//!< its covariance [m^2]
	Eigen::Vector2d z;	//!< its pixel in the current image [px]
};

/** Robust Gauss-Newton on the reprojection error of the used correspondences
 * (use[i] != 0; all if empty) from T_init (= T_curr_ref): Huber kernel
 * (huber_k sigmas), each residual's covariance sigma_px^2 I plus the
 * landmark's covariance projected. The solution's cov_T_ref_curr is the
 * covariance of T_ref_curr (left convention, unscaled). */
geometry::TPoseSolution solveImagePose(
	const TPinholeCalib& calib, const std::vector<TImageCorrespondence>& c, const std::vector<uint8_t>& use,
	const Eigen::Isometry3d& T_init, double sigma_px, double huber_k, int max_iterations);

}  // namespace shadyloc::localisation
