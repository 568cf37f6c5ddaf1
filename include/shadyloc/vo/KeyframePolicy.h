/* ShadyLoc — when a tracked frame becomes a keyframe: a policy object outside
 * the VO. StereoVO asks its policy after a frame is tracked (track()), and the
 * caller decides (commit()): follow the policy, or force or forbid the
 * keyframe. So one schedule can drive two VOs (the mono and the invariant
 * channel of a dual-channel map): track both, decide once, commit both:
 *
 *     const auto a = voMono.track(...), b = voInv.track(...);
 *     const bool kf = a.keyframe_wanted || b.keyframe_wanted;
 *     voMono.commit(kf ? KeyframeDecision::Make : KeyframeDecision::Skip);
 *     voInv.commit(kf ? KeyframeDecision::Make : KeyframeDecision::Skip);
 *
 * The first keyframe and a re-initialisation after a tracking gap are not
 * the policy's to decide: a VO without a keyframe cannot track.
 */
#pragma once

#include <Eigen/Geometry>

#include <cstddef>
#include <memory>

namespace shadyloc::vo
{
/** What a policy sees of a tracked frame. */
struct TKeyframeQuery
{
	size_t frame = 0;  //!< frame index
	Eigen::Isometry3d T_kf_curr = Eigen::Isometry3d::Identity();  //!< the frame in the current keyframe
	size_t inliers = 0;	 //!< inliers of the frame's pose
	size_t keyframe_landmarks = 0;	//!< landmarks of the current keyframe
	size_t frames_since_keyframe = 0;  //!< frames since the keyframe was made (1 = the next frame)
};

/** A keyframe policy: stateless, so one instance can be shared. */
class KeyframePolicy
{
   public:
	using Ptr = std::shared_ptr<const KeyframePolicy>;
	virtual ~KeyframePolicy() = default;
	/** True if the tracked frame described by q should become a keyframe. */
	virtual bool wantKeyframe(const TKeyframeQuery& q) const = 0;
};

/** Options of MotionKeyframePolicy (TStereoVOOptions' kf_* keys). */
struct TMotionKeyframePolicyOptions
{
	double kf_translation = 1.0;  //!< beyond this distance from the keyframe [m]
	double kf_rotation_deg = 10.0;	//!< ... or this rotation [deg]
	double kf_min_tracked_fraction = 0.35;	//!< ... or when inliers / keyframe landmarks fall below this
	int kf_min_inliers = 40;  //!< ... or when inliers fall below this
};

/** The VO's default policy: a new keyframe when the motion from the keyframe
 * is large or the overlap with it small. */
class MotionKeyframePolicy : public KeyframePolicy
{
   public:
	using TOptions = TMotionKeyframePolicyOptions;
	explicit MotionKeyframePolicy(const TOptions& o = TOptions()) : m_opts(o) {}
	bool wantKeyframe(const TKeyframeQuery& q) const override;
	const TOptions& options() const { return m_opts; }

   private:
	TOptions m_opts;
};

/** The caller's decision for a tracked frame (StereoVO::commit). */
enum class KeyframeDecision
{
	Policy,	 //!< as the VO's policy wants (TFrameResult::keyframe_wanted)
	Make,  //!< force a keyframe
	Skip  //!< forbid a keyframe
};

}  // namespace shadyloc::vo
