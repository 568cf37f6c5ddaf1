/* ShadyLoc — the cross-product matrix, shared by the pose solver and the
 * covariance code (private to src/geometry). */
#pragma once

#include <Eigen/Core>

namespace shadyloc::geometry
{
/** [v]x: skew(v) * w == v.cross(w). */
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v)
{
	Eigen::Matrix3d S;
	S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
	return S;
}
}  // namespace shadyloc::geometry
