/* ShadyLoc — keyframe policies. */
#include <shadyloc/vo/KeyframePolicy.h>

#include <cmath>

namespace shadyloc::vo
{
bool MotionKeyframePolicy::wantKeyframe(const TKeyframeQuery& q) const
{
	const auto& o = m_opts;
	const double rotDeg = Eigen::AngleAxisd(q.T_kf_curr.linear()).angle() * 180.0 / M_PI;
	const double frac = q.keyframe_landmarks == 0 ? 0.0 : double(q.inliers) / q.keyframe_landmarks;
	return q.T_kf_curr.translation().norm() > o.kf_translation || rotDeg > o.kf_rotation_deg ||
		   frac < o.kf_min_tracked_fraction || static_cast<int>(q.inliers) < o.kf_min_inliers;
}

}  // namespace shadyloc::vo
