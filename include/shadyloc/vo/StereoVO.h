/* ShadyLoc — keyframe-based stereo visual odometry (McManus et al. 2014,
 * Section II-A), one class for both image channels: it sees only a grey
 * CV_8UC1 stereo pair, monochrome or illumination-invariant.
 *
 * StereoVO composes stages that the localisers reuse:
 *   features::StereoFeatureExtractor  stereo measurements of the frame;
 *   KeyframeMatcher (vo/KeyframeMatcher.h)  the keyframe's landmarks
 *       projected with the pose predicted by the motion model (constant
 *       velocity, or the caller's prior), BRIEF in a region around each,
 *       sub-pixel patch refinement;
 *   RelativePoseEstimator (vo/RelativePoseEstimator.h)  RANSAC with the
 *       prediction as a hypothesis, robust solve, re-selection, covariance;
 *   KeyframePolicy (vo/KeyframePolicy.h)  whether a tracked frame becomes a
 *       keyframe; the caller may override it (track() + commit()).
 * StereoVO itself keeps the state: keyframes, the motion model, the count of
 * untracked frames. Frames that cannot be tracked are reported (status), get
 * the predicted pose, and tracking resumes at the next good frame.
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/geometry/PoseCovariance.h>
#include <shadyloc/geometry/PoseSolver.h>
#include <shadyloc/geometry/StereoCamera.h>
#include <shadyloc/vo/Keyframe.h>
#include <shadyloc/vo/KeyframeMatcher.h>
#include <shadyloc/vo/KeyframePolicy.h>
#include <shadyloc/vo/RelativePoseEstimator.h>

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/system/COutputLogger.h>

#include <Eigen/Geometry>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::vo
{
/** What happened to a frame (the `status` column of the stats CSV). */
enum class FrameStatus
{
	Ok,	 //!< tracked against the keyframe
	First,	//!< first keyframe of the run (defines the world frame)
	FewFeatures,  //!< too few stereo measurements: not tracked, predicted pose
	FewMatches,	 //!< too few BRIEF matches to the keyframe: predicted pose
	FewInliers,	 //!< RANSAC found too few inliers: predicted pose
	SolverFailed,  //!< Gauss-Newton diverged or degenerate: predicted pose
	WildMotion,	 //!< solution jumps beyond the motion bounds: rejected, predicted pose
	Reinit	//!< lost too long: a new keyframe starts a new chain segment here
};
std::string toString(FrameStatus s);
/** True when the frame's pose came from measurements (Ok, First, Reinit). */
inline bool isTracked(FrameStatus s)
{
	return s == FrameStatus::Ok || s == FrameStatus::First || s == FrameStatus::Reinit;
}


/** Frame b's pose in frame a, each given in a keyframe of the VO's list
 * (`T_refA_a` in keyframe refA, `T_refB_b` in refB, refA <= refB), composed
 * along the keyframes' links between them; nullopt when a chain break
 * (a predicted link) lies between, or a reference is out of the list. */
std::optional<geometry::TPoseWithCov> poseAlongChain(
	const std::vector<TKeyframe>& keyframes, size_t refA, const geometry::TPoseWithCov& T_refA_a, size_t refB,
	const geometry::TPoseWithCov& T_refB_b);

/** Stage times of one frame [ms]. */
struct TVOTimings
{
	double detect = 0, stereo = 0, describe = 0, match = 0, ransac = 0, solve = 0, total = 0;
};

/** Result of one frame. */
struct TFrameResult
{
	size_t frame = 0;
	double timestamp = 0;  //!< [s]
	FrameStatus status = FrameStatus::Ok;
	bool keyframe = false;	//!< this frame became a keyframe
	/** The keyframe policy's proposal for this tracked frame (Ok frames only;
	 * what commit(KeyframeDecision::Policy) follows). */
	bool keyframe_wanted = false;
	size_t features = 0;  //!< FAST corners kept in the left image
	size_t stereo = 0;	//!< stereo measurements (with landmark)
	size_t tracked = 0;	 //!< BRIEF matches to the keyframe (after refinement)
	size_t inliers = 0;	 //!< RANSAC / solver inliers
	double rms_px = 0;	//!< solver RMS residual [px]
	Eigen::Isometry3d T_world_curr = Eigen::Isometry3d::Identity();	 //!< left camera in the first frame
	Eigen::Isometry3d T_kf_curr = Eigen::Isometry3d::Identity();  //!< relative to the reference keyframe
	geometry::Matrix6d cov_kf_curr = geometry::Matrix6d::Zero();  //!< of T_kf_curr (left convention)
	TVOTimings ms;
};

/** A tracked frame's place on the VO's chain: its reference keyframe (the
 * frame itself at First/Reinit, else the last keyframe before it) and its
 * pose there, for poseAlongChain. */
struct TChainReference
{
	size_t ref = 0;
	geometry::TPoseWithCov T_ref_f;
};
/** `r`'s chain reference, given the VO's keyframes after the frame and their
 * count before it; nullopt for an untracked frame or counts that disagree. */
std::optional<TChainReference> chainReference(
	const TFrameResult& r, const std::vector<TKeyframe>& keyframes, size_t keyframesBefore);

/** Options of StereoVO ([vo] in config/vo.ini). */
struct TStereoVOOptions : public mrpt::config::CLoadableOptions
{
	double search_radius_px = 40;  //!< BRIEF search window around each predicted projection [px]
	double search_radius_lost_px = 80;	//!< window after a failure or when the first try finds too few [px]
	int max_hamming = 90;  //!< largest BRIEF distance of a match [bits of 256]
	double match_ratio = 0.95;	//!< best must be < ratio * second best distance in the window
	double refine_min_zncc = 0.5;  //!< patch refinement must correlate this well, or the match is dropped
	int refine_radius = 2;	//!< patch refinement moves at most this far from the BRIEF match [px]
	int refine_iterations = 5;	//!< Gauss-Newton steps after the 2D parabola (features::refinePatch2D); 0 = parabola only
	int min_stereo = 20;  //!< fewer stereo measurements: FewFeatures
	int min_matches = 12;  //!< fewer matches to the keyframe: FewMatches
	int min_inliers = 10;  //!< fewer inliers: FewInliers
	/** Pose from near landmarks when there are enough: keyframe landmarks with a
	 * true disparity fx*b/Z below this are left out of RANSAC and the solve
	 * when at least `near_min_matches` matches remain (0 = off) [px]. Far
	 * landmarks constrain rotation but barely translation, and their measured
	 * disparity can be biased (corners on depth discontinuities: the foreground
	 * texture dominates the patch), which shortens every step (docs/vo.md). */
	double near_min_disparity = 0.0;
	int near_min_matches = 40;	//!< matches needed to drop the far ones (else all are used)
	double ransac_threshold_px = 4.0;  //!< RANSAC inlier bound on |(duL, dv, duR)| [px]
	int ransac_iterations = 200;  //!< RANSAC upper bound
	double sigma_px = 0.5;	//!< measurement noise for the solver [px]
	double huber_k = 1.0;  //!< Huber threshold [sigmas]
	/** Solve by two-view bundle adjustment (keyframe landmarks re-estimated,
	 * geometry::solveStereoPoseTwoView) instead of with fixed landmarks whose
	 * covariance is folded into the residuals (geometry::solveStereoPose). */
	bool two_view_ba = true;
	/** Score the motion model's prediction as a RANSAC hypothesis besides the
	 * random minimal sets. */
	bool ransac_prediction = true;
	/** RANSAC's preference for hypotheses near the prediction
	 * (geometry::TRansacOptions::prior_sigma_m), 0 = off [m per frame]. */
	double ransac_prior_sigma_m = 0.15;
	double kf_translation = 1.0;  //!< new keyframe beyond this distance from the keyframe [m]
	double kf_rotation_deg = 10.0;	//!< ... or this rotation [deg]
	double kf_min_tracked_fraction = 0.35;	//!< ... or when inliers / keyframe landmarks fall below this
	int kf_min_inliers = 40;  //!< ... or when inliers fall below this
	double max_step_translation = 2.0;	//!< per-frame motion above this is rejected (WildMotion) [m]
	double max_step_rotation_deg = 30.0;  //!< per-frame rotation above this is rejected [deg]
	int max_lost_frames = 3;  //!< after this many untracked frames in a row, re-initialise (Reinit)
	bool constant_velocity = true;	//!< predict with the last motion (else identity)

	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;
	void validate() const;	//!< throws std::invalid_argument naming the option
};

/** The stages' options from the VO's ([vo] in config/vo.ini). */
TKeyframeMatcherOptions matcherOptionsFrom(const TStereoVOOptions& o);
TRelativePoseOptions poseEstimatorOptionsFrom(const TStereoVOOptions& o);
TMotionKeyframePolicyOptions keyframePolicyOptionsFrom(const TStereoVOOptions& o);

class StereoVO : public mrpt::system::COutputLogger
{
   public:
	using TOptions = TStereoVOOptions;
	/** With the policy MotionKeyframePolicy(keyframePolicyOptionsFrom(o)). */
	StereoVO(const TOptions& o = TOptions(), const features::TStereoFeatureOptions& fo = {});

	/** One rectified grey stereo pair (CV_8UC1, equal sizes): track() then
	 * commit() as the policy wants. prior_T_prev_curr, if given, replaces the
	 * constant-velocity prediction (e.g. the baseline channel's VO predicting
	 * for the invariant one). */
	TFrameResult process(
		const cv::Mat& left8, const cv::Mat& right8, const geometry::TStereoCalib& calib,
		double timestamp, const Eigen::Isometry3d* prior_T_prev_curr = nullptr);

	/** The first half of process(): the frame is tracked and the result is
	 * final except whether a tracked frame becomes a keyframe
	 * (keyframe_wanted says what the policy wants). commit() must follow
	 * before the next track(). */
	TFrameResult track(
		const cv::Mat& left8, const cv::Mat& right8, const geometry::TStereoCalib& calib,
		double timestamp, const Eigen::Isometry3d* prior_T_prev_curr = nullptr);
	/** track() on measurements already extracted (StereoFeatureExtractor with
	 * this VO's feature options, e.g. shared with a localiser of the same
	 * channel): the frame's measurements are kept as a keyframe's if it
	 * becomes one, hence taken by value. */
	TFrameResult track(
		features::TStereoFrame frame, const geometry::TStereoCalib& calib, double timestamp,
		const Eigen::Isometry3d* prior_T_prev_curr = nullptr);
	/** The second half: a tracked (Ok) frame becomes a keyframe as decided;
	 * other frames ignore the decision (First and Reinit frames are keyframes
	 * anyway, untracked ones cannot be). Returns the final result. */
	TFrameResult commit(KeyframeDecision d = KeyframeDecision::Policy);

	/** Replaces the keyframe policy (shared: a policy is stateless). */
	void setKeyframePolicy(KeyframePolicy::Ptr p);
	const KeyframePolicy& keyframePolicy() const { return *m_policy; }

	const std::vector<TKeyframe>& keyframes() const { return m_keyframes; }
	const TOptions& options() const { return m_opts; }
	const features::StereoFeatureExtractor& extractor() const { return m_extractor; }
	const KeyframeMatcher& matcher() const { return m_matcher; }
	const RelativePoseEstimator& poseEstimator() const { return m_poseEstimator; }
	/** Last frame-to-frame motion estimate (the constant-velocity model). */
	const Eigen::Isometry3d& lastMotion() const { return m_velocity; }
	void reset();

   private:
	TFrameResult trackMeasured(
		features::TStereoFrame&& fr, const geometry::TStereoCalib& calib, double timestamp,
		const Eigen::Isometry3d* prior, std::chrono::steady_clock::time_point tStart);
	void addKeyframe(
		size_t frame, double timestamp, const Eigen::Isometry3d& T_world_kf, const geometry::Matrix6d& cov,
		bool chainBreak, std::vector<features::TStereoMeasurement>&& meas, const geometry::TStereoCalib& calib);

	TOptions m_opts;
	features::StereoFeatureExtractor m_extractor;
	KeyframeMatcher m_matcher;
	RelativePoseEstimator m_poseEstimator;
	KeyframePolicy::Ptr m_policy;
	std::vector<TKeyframe> m_keyframes;
	geometry::TStereoCalib m_kfCalib;  //!< calibration of the frame m_keyframes.back() was made from
	size_t m_frame = 0;
	int m_lost = 0;	 //!< untracked frames in a row
	Eigen::Isometry3d m_T_world_prev = Eigen::Isometry3d::Identity();
	Eigen::Isometry3d m_velocity = Eigen::Isometry3d::Identity();  //!< T_prev_curr of the last tracked step

	/** A tracked frame between track() and commit(). */
	struct TPending
	{
		bool active = false;  //!< track() ran, commit() not yet
		bool candidate = false;	 //!< a tracked frame that may become a keyframe
		TFrameResult res;
		std::vector<features::TStereoMeasurement> meas;
		geometry::TStereoCalib calib;
		std::chrono::steady_clock::time_point start;
	} m_pending;
};

}  // namespace shadyloc::vo
