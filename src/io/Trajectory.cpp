/* ShadyLoc — the trajectory type. */
#include <shadyloc/io/Trajectory.h>

#include <mrpt/math/CMatrixFixed.h>

#include <algorithm>
#include <cmath>

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

std::vector<std::pair<size_t, size_t>> associate(const Trajectory& gt, const Trajectory& est, double maxDt)
{
	std::vector<std::pair<size_t, size_t>> out;
	if (gt.empty()) return out;
	size_t g = 0;
	long lastG = -1;
	for (size_t e = 0; e < est.size(); e++)
	{
		while (g + 1 < gt.size() && std::abs(gt[g + 1].t - est[e].t) <= std::abs(gt[g].t - est[e].t)) g++;
		if (std::abs(gt[g].t - est[e].t) <= maxDt && static_cast<long>(g) != lastG)
		{
			out.emplace_back(g, e);
			lastG = static_cast<long>(g);
		}
	}
	return out;
}

}  // namespace shadyloc::io
