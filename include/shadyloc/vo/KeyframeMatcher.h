/* ShadyLoc — the keyframe matcher: a stage of the stereo VO that the
 * localisers reuse. Given a keyframe's landmarks, a predicted pose of the
 * current frame and the current frame's stereo measurements, it finds which
 * measurement belongs to which landmark:
 *   1. project each landmark with the predicted pose;
 *   2. search a region around the projection: a fixed circle (the VO; a wider
 *      circle when the first try finds too few), or the gate of the
 *      prediction's covariance ("active search", McManus et al. 2014,
 *      Section II-B; Davison, "Real-Time Simultaneous Localisation and
 *      Mapping with a Single Camera", ICCV 2003);
 *   3. BRIEF: the smallest Hamming distance in the region, a ratio test
 *      against the second smallest, one landmark per measurement;
 *   4. sub-pixel: the keyframe's stored patch correlated (ZNCC) in the
 *      current left image, climbing to the peak, parabola then Gauss-Newton
 *      (features::refinePatch2D).
 * With `warp`, steps 3 and 4 see the current image through each landmark's
 * plane-induced warp at the predicted pose (features/PatchWarp.h) wherever the
 * landmark has a surface normal and the warp is far from the identity.
 * The output is a set of geometry::TStereoCorrespondence for the
 * relative-pose estimator (vo/RelativePoseEstimator.h).
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/geometry/PoseSolver.h>
#include <shadyloc/geometry/StereoCamera.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <vector>

namespace shadyloc::vo
{
/** How the search region around each projected landmark is chosen. */
enum class SearchRegion
{
	Circle,	 //!< a fixed radius (search_radius_px, then search_radius_lost_px)
	Gate  //!< the chi-square gate of the predicted measurement's covariance
};

/** Options of KeyframeMatcher (the VO fills them from TStereoVOOptions,
 * see matcherOptionsFrom()). */
struct TKeyframeMatcherOptions
{
	SearchRegion region = SearchRegion::Circle;
	double search_radius_px = 40;  //!< Circle: radius around each projection [px]
	double search_radius_lost_px = 80;	//!< Circle: radius after a failure, or when the first try finds < min_matches [px]
	int min_matches = 12;  //!< Circle: fewer BRIEF matches than this trigger the wide retry
	/** Gate: a measurement z is a candidate when (z - z_pred)^T S^-1 (z - z_pred)
	 * <= gate_chi2 over (uL, v, uR); 11.34 is the 99 % quantile of chi^2 with
	 * 3 degrees of freedom. */
	double gate_chi2 = 11.34;
	/** Gate: every axis of the gate ellipsoid is at least this long (corners
	 * are integer pixels; a tiny covariance must not exclude them) [px]. */
	double gate_min_px = 3.0;
	double gate_max_px = 80.0;	//!< Gate: ... and at most this long (bounds the search) [px]
	/** Gate: an axis longer than gate_max_px is clamped to it (true, the
	 * VO), or the landmark is not searched at all and counted as an overflow
	 * (false, the localisers: a clipped gate silently excludes the true
	 * match, so a caller that sees many overflows declares itself lost). */
	bool gate_clamp = true;
	/** Gate: when > 0, gate_max_px bounds only the prediction's part of the
	 * gate (pose covariance and pixel noise: is the pose known well enough to
	 * search?), and the whole gate, with the landmark's own covariance, may
	 * reach this length [px]. A landmark triangulated over a short baseline
	 * and seen from a viewpoint B metres aside is uncertain along one
	 * direction by about B / baseline times its disparity noise, whatever its
	 * depth (a thin gate along the epipolar line, not a lost pose): 0.5 m
	 * aside of the simulator's 0.12 m rig makes it 14 px, 1 m 30 px, 3.5 m
	 * 92 px (docs/localisation.md, "The other lane"). A landmark whose whole
	 * gate exceeds it is not searched and is counted in
	 * TGateStats::too_uncertain, not as an overflow. 0: gate_max_px bounds
	 * the whole gate (the VO). */
	double gate_landmark_max_px = 0.0;
	double sigma_px = 0.5;	//!< Gate: measurement noise per pixel coordinate [px]
	int max_hamming = 90;  //!< largest BRIEF distance of a match [bits of 256]
	double match_ratio = 0.95;	//!< best must be < ratio * second best distance in the region
	double refine_min_zncc = 0.5;  //!< the refined patch must correlate this well, or the match is dropped
	int refine_radius = 2;	//!< refinement climbs at most this far from the BRIEF match [px]
	int refine_iterations = 5;	//!< Gauss-Newton steps after the parabola (features::refinePatch2D)
	/** Keep only landmarks of true disparity >= this when at least
	 * near_min_matches remain (0 = off) [px] (TStereoVOOptions::near_min_disparity). */
	double near_min_disparity = 0.0;
	int near_min_matches = 40;
	/** Warp the BRIEF tests and the refinement patch of every landmark with a
	 * surface normal by the plane it lies on, seen from the predicted pose
	 * (needs TKeyframeMatchInput::brief). */
	bool warp = false;
	/** ... only where the warp moves a pixel offset by more than this share
	 * of itself (warpDistortion): below it the unwarped tests agree anyway
	 * and cost less. */
	double warp_min_distortion = 0.1;
	/** searchPatches: the patch climbs at most this far from the landmark's
	 * projection [px]. */
	int patch_search_radius_px = 2;
	/** searchPatches: the patch must correlate this well where it is found
	 * (no descriptor vouches for it, unlike refine_min_zncc's matches). */
	double patch_min_zncc = 0.8;
	/** searchPatches: the right-image column is searched within this of the
	 * predicted one [px] ... */
	int patch_stereo_range_px = 2;
	double patch_stereo_min_zncc = 0.8;	 //!< ... and must correlate this well (7x7 windows)
};

/** Input of one matching: the keyframe, the current frame and the prediction. */
struct TKeyframeMatchInput
{
	/** The keyframe's stereo measurements: landmarks P in the keyframe's left
	 * camera, descriptors, patches (TKeyframe::meas). */
	const std::vector<features::TStereoMeasurement>* landmarks = nullptr;
	/** The keyframe's calibration: each correspondence carries it with the
	 * landmark's measurement there (TStereoCorrespondence::z_ref, calib_ref). */
	geometry::TStereoCalib calib_kf;
	/** The current frame's measurements and left image (the one its patches
	 * were cut from: StereoFeatureExtractor's output). */
	const features::TStereoFrame* frame = nullptr;
	geometry::TStereoCalib calib;  //!< the current frame's calibration
	Eigen::Isometry3d T_curr_kf_pred = Eigen::Isometry3d::Identity();  //!< predicted keyframe in current camera
	/** Covariance of T_curr_kf_pred (left perturbation, translation first
	 * [m^2, rad^2]); used by the Gate region only. */
	geometry::Matrix6d cov_T_curr_kf_pred = geometry::Matrix6d::Zero();
	/** Circle: start with search_radius_lost_px and do not retry (the VO sets
	 * it after an untracked frame). */
	bool wide = false;
	/** The BRIEF pattern the landmarks' descriptors were made with: warped
	 * matching (TKeyframeMatcherOptions::warp) maps it through each
	 * landmark's warp; null = descriptors compared unwarped (ORB's oriented
	 * tests; the patches are still warped). */
	const features::BriefExtractor* brief = nullptr;
	/** Per current measurement, 1 where it is already matched (to a nearer
	 * keyframe's landmark): a landmark whose descriptor match is such a
	 * measurement is neither refined nor returned. The descriptor search
	 * itself still sees every measurement, so the other matches are the
	 * ones it makes without the mask. Null = none taken. */
	const std::vector<uint8_t>* taken = nullptr;
};

/** A landmark's predicted stereo measurement and its covariance. */
struct TPredictedMeasurement
{
	bool ok = false;  //!< false if the landmark is behind (or within 0.1 m of) the camera
	Eigen::Vector3d z = Eigen::Vector3d::Zero();  //!< predicted (uL, v, uR) [px]
	/** Cov(z) = J_P Cov(P) J_P^T + J_xi Cov(T) J_xi^T + sigma^2 I [px^2]. */
	Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
};

/** What the Gate saw of the landmarks (TKeyframeMatchOutput::gate). */
struct TGateStats
{
	int predicted = 0;	//!< landmarks in front of the camera, predicted inside the image
	int overflow = 0;  //!< ... whose gate exceeded gate_max_px (not searched when !gate_clamp)
	/** ... whose whole gate exceeded gate_landmark_max_px while the
	 * prediction's part did not (not searched; gate_landmark_max_px > 0 only). */
	int too_uncertain = 0;
	double median_axis_px = 0;	//!< median longest gate axis of the predicted ones (before clamping) [px]
};

/** Output of one matching. */
struct TKeyframeMatchOutput
{
	std::vector<geometry::TStereoCorrespondence> corr;	//!< refined correspondences, in landmark order
	std::vector<int> landmark;	//!< per correspondence: index into the input landmarks
	std::vector<int> measurement;  //!< per correspondence: index into frame->meas (the BRIEF match)
	int descriptor_matches = 0;	 //!< BRIEF matches of the last search (before refinement)
	bool widened = false;  //!< Circle: the wide retry ran
	bool near_only = false;	 //!< far landmarks were left out (near_min_disparity)
	int warped = 0;	 //!< correspondences found through a warp (TKeyframeMatcherOptions::warp)
	TGateStats gate;  //!< Gate region only
};

/** The keyframe matcher (see the file comment). Stateless: one instance can
 * serve several threads. */
class KeyframeMatcher
{
   public:
	using TOptions = TKeyframeMatcherOptions;
	explicit KeyframeMatcher(const TOptions& o = TOptions());

	/** All four steps. */
	void match(const TKeyframeMatchInput& in, TKeyframeMatchOutput& out) const;

	/** Search by projection with patches, for a pose already known to a few
	 * pixels (a localiser's second pass, at its first solve): every landmark
	 * whose `skip` flag is not set is projected at in.T_curr_kf_pred, its
	 * patch (warped where warpOf says so) climbed to from there (at most
	 * patch_search_radius_px, ZNCC >= patch_min_zncc), and its right-image
	 * column found along the row near the predicted disparity
	 * (features::matchAlongRow). No live corner is needed: on the simulator
	 * a patch finds about three times the landmarks FAST re-detects
	 * (docs/localisation.md, "Search by projection with patches").
	 * `occupied` (one byte per live pixel, 0 = free) keeps two landmarks off
	 * one live pixel; found pixels are marked. Appends to out, with
	 * measurement -1. */
	void searchPatches(
		const TKeyframeMatchInput& in, const std::vector<uint8_t>& skip, cv::Mat& occupied,
		TKeyframeMatchOutput& out) const;

	/** Steps 1-3 with a given region: matchOf[j] = index of the measurement
	 * matched to landmark j, or -1; returns the number of matches. For the
	 * Circle region, `radius` [px] is the circle's; the Gate ignores it. */
	int searchDescriptors(
		const TKeyframeMatchInput& in, double radius, std::vector<int>& matchOf, TGateStats* gate = nullptr) const;

	/** The predicted measurement of landmark P_kf (covariance cov_P [m^2]) at
	 * T_curr_kf (covariance cov_T, left convention) with pixel noise sigma_px. */
	static TPredictedMeasurement predict(
		const geometry::TStereoCalib& calib, const Eigen::Isometry3d& T_curr_kf, const geometry::Matrix6d& cov_T,
		const Eigen::Vector3d& P_kf, const Eigen::Matrix3d& cov_P, double sigma_px);

	/** The gate's matrix: S with its eigenvalues clamped so that every axis of
	 * {r : r^T G^-1 r <= gate_chi2} lies in [gate_min_px, gate_max_px]. */
	Eigen::Matrix3d gateMatrix(const Eigen::Matrix3d& S) const;
	/** The same from S's decomposition (S symmetrised). */
	Eigen::Matrix3d gateMatrix(const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>& es) const;

	const TOptions& options() const { return m_opts; }

	/** The warp of landmark `lm` at the input's predicted pose, when warping
	 * applies to it (warp on, a normal, a warp far enough from the
	 * identity); false = compare it unwarped. Descriptors are warped only
	 * with a BRIEF pattern (TKeyframeMatchInput::brief). */
	bool warpOf(const TKeyframeMatchInput& in, const features::TStereoMeasurement& lm, Eigen::Matrix2d& A) const;

   private:
	TOptions m_opts;
};

}  // namespace shadyloc::vo
