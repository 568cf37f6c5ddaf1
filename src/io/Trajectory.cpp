/* ShadyLoc — the trajectory type. */
#include <shadyloc/io/Trajectory.h>

#include <mrpt/math/CMatrixFixed.h>

#include <algorithm>

namespace shadyloc::io
{
void sortByTime(Trajectory& traj)
{
	std::stable_sort(traj.begin(), traj.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
}

Eigen::Isometry3d toIsometry(const mrpt::poses::CPose3D& p)
{
	Eigen::Isometry3d T;
	T.matrix() = p.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>().asEigen();
	return T;
}

mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& T)
{
	mrpt::math::CMatrixDouble44 m;
	m.asEigen() = T.matrix();
	return mrpt::poses::CPose3D(m);
}

}  // namespace shadyloc::io
