/* ShadyLoc — the accept stage of a localiser: is a solve a fix?
 *
 * Two tests, both Mahalanobis on the sum of the covariances:
 *  - the solve against the prediction of the system's track (accepted fixes
 *    propagated by VO; never a seed the localiser's own solves produced, so
 *    a wrong place cannot validate itself);
 *  - the frame-to-frame motion of this solve and the last consistent one
 *    against VO's increment (the paper's test, McManus et al. 2014,
 *    Section III-B). A rejected solve is never a reference.
 * Confirmation: a new place hypothesis (the start, a global search, a jump)
 * needs K consecutive motion-tested consistent frames; while the system's
 * track is confirmed, a consistent solve is a fix at once (per-localiser
 * confirmation cost about p^3 of the frames for a per-frame success p).
 * Tested alone, without images (tests/unit/test_localisation_stages.cpp).
 */
#pragma once

#include <shadyloc/geometry/PoseCovariance.h>

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace shadyloc::localisation
{
/** A pose relative to a map keyframe with its covariance (left perturbation,
 * translation first [m^2, rad^2]). */
struct TKeyframePose
{
	bool valid = false;
	uint32_t kf = 0;  //!< map keyframe id
	Eigen::Isometry3d T_kf_live = Eigen::Isometry3d::Identity();  //!< live left camera in the keyframe's left camera
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();

	geometry::TPoseWithCov withCov() const
	{
		geometry::TPoseWithCov p;
		p.T = T_kf_live;
		p.cov = cov;
		return p;
	}
};

/** VO's motion from the previous frame to this one. */
struct TMotion
{
	bool valid = false;
	Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();  //!< left perturbation [m^2, rad^2]
};

struct TAcceptanceOptions
{
	double prediction_chi2 = 16.81;	 //!< chi^2 with 6 dof (99 %) [-]
	double motion_chi2 = 22.46;	 //!< [-]
	int consistent_frames = 2;	//!< K: motion-tested consistent frames that confirm a new place
	/** A solve whose translation sigma is at least this (0 = off) must pass
	 * the prediction test at uncertain_prediction_chi2 instead [m]. */
	double uncertain_sigma_m = 0;
	double uncertain_prediction_chi2 = 16.81;  //!< [-]
};

/** One localiser's solve of one frame. */
struct TSolve
{
	size_t frame = 0;
	TKeyframePose pose;	 //!< valid: T_kf_live and cov of the solve
};

enum class AcceptanceVerdict
{
	Fix,  //!< consistent, and the place is confirmed (by K frames or the system's track)
	Unconfirmed,  //!< consistent, a new place not yet confirmed
	Uncounted,	//!< consistent, but too uncertain to count or to be a reference
	PredictionInconsistent,
	MotionInconsistent
};
std::string toString(AcceptanceVerdict v);

struct TAcceptance
{
	AcceptanceVerdict verdict = AcceptanceVerdict::Unconfirmed;
	double prediction_d2 = -1;	//!< -1: not run (no prediction)
	double motion_d2 = -1;	//!< -1: not run (no reference of the previous frame)
	int consistent = 0;	 //!< consecutive consistent motion-tested frames after this one
	bool fix() const { return verdict == AcceptanceVerdict::Fix; }
};

/** T_a_b with covariance between two map keyframes (the map's chain). */
using KeyframeLink = std::function<geometry::TPoseWithCov(uint32_t a, uint32_t b)>;

class FixAcceptance
{
   public:
	explicit FixAcceptance(const TAcceptanceOptions& o = {}) : m_opts(o) {}

	/** Judges a solve. `prediction` (in the solve's keyframe, may be invalid)
	 * comes from the system's track; `trackConfirmed` tells whether that
	 * track is a confirmed place; `countable` is false for a solve too
	 * uncertain to count towards K (it may still be rejected). */
	TAcceptance judge(
		const TSolve& s, const TKeyframePose& prediction, const TMotion& motion, bool trackConfirmed, bool countable,
		const KeyframeLink& link);

	/** A frame without a solve: consistency must start again. */
	void noSolve();

	/** A verified place (the global search) at `frame`: the first consistent
	 * frame of a new hypothesis, and the next frame's motion reference. */
	void startFrom(size_t frame, const TKeyframePose& place);

	void reset();
	int consistent() const { return m_consistent; }

   private:
	double predictionGate(const TSolve& s) const;

	TAcceptanceOptions m_opts;
	std::optional<TSolve> m_ref;  //!< the last consistent solve (the motion test's reference)
	int m_consistent = 0;
	bool m_confirmed = false;
};

using geometry::mahalanobis2;
/** The prediction test's statistic: `solve` against `pred` re-expressed in
 * the solve's keyframe through `link`, on the sum of their covariances. */
double predictionDistance2(const TKeyframePose& solve, const TKeyframePose& pred, const KeyframeLink& link);

/** An accepted solve fused with the prediction it was tested against (both
 * in the solve's keyframe): the Kalman update of the prediction by the
 * solve in the tangent space at the prediction. Along what the solve's
 * landmarks constrain weakly (depth in a far-field scene) the track carries
 * the pose; elsewhere the solve. The solve itself when the covariances are
 * not positive definite. */
geometry::TPoseWithCov fuseWithPrediction(const geometry::TPoseWithCov& solve, const geometry::TPoseWithCov& prediction);

}  // namespace shadyloc::localisation
