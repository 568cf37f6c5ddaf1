/* ShadyLoc — the library's one trajectory type: timestamped rigid poses.
 * Importers, the simulator, the VO, the evaluation and the renderer all hand
 * trajectories around as this; io/Tum.h reads and writes it as TUM text. */
#pragma once

#include <mrpt/poses/CPose3D.h>

#include <Eigen/Geometry>

#include <utility>
#include <vector>

namespace shadyloc::io
{
/** One timestamped pose. The frames are the trajectory's: usually
 * T_world_body (the body's pose in the world), e.g. T_world_left. */
struct TStampedPose
{
	double t = 0;  //!< timestamp [s] (since the Unix epoch for real and simulated data)
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();  //!< the pose at t (rotation, translation [m])
};
using Trajectory = std::vector<TStampedPose>;

/** Sorts by timestamp, keeping the order of equal stamps (stable). */
void sortByTime(Trajectory& traj);

/** Pairs (gt index, est index) with |t_gt - t_est| <= maxDt [s], each
 * estimate to its nearest ground-truth stamp, in time order, one-to-one.
 * Both must be in time order (sortByTime). Here, not in `eval`, because the
 * localisation's evaluation and the survey join their frames to ground
 * truth with it too. */
std::vector<std::pair<size_t, size_t>> associate(const Trajectory& gt, const Trajectory& est, double maxDt);

/** MRPT pose <-> isometry, element for element (no re-orthonormalisation). */
Eigen::Isometry3d toIsometry(const mrpt::poses::CPose3D& p);
mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& T);

}  // namespace shadyloc::io
