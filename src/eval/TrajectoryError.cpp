/* ShadyLoc — trajectory error metrics. */
#include <shadyloc/eval/TrajectoryError.h>
#include <shadyloc/geometry/PoseSolver.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace shadyloc::eval
{
namespace
{
double angleDeg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI; }
}  // namespace

TTrajectoryErrors computeErrors(const Trajectory& gtAll, const Trajectory& estAll, double maxDt)
{
	const auto pairs = associate(gtAll, estAll, maxDt);
	if (pairs.size() < 3)
		throw std::runtime_error(
			"trajectory error: only " + std::to_string(pairs.size()) +
			" poses associated by timestamp (need >= 3; check the time bases and --max-dt)");
	TTrajectoryErrors r;
	r.matched = pairs.size();
	std::vector<Eigen::Isometry3d> G, E;
	for (const auto& p : pairs)
	{
		G.push_back(gtAll[p.first].T);
		E.push_back(estAll[p.second].T);
	}
	const size_t n = G.size();
	// Alignment on positions, no scale (stereo has metric scale).
	std::vector<Eigen::Vector3d> src, dst;
	for (size_t i = 0; i < n; i++)
	{
		src.push_back(E[i].translation());
		dst.push_back(G[i].translation());
	}
	if (!geometry::rigidTransform3D(src, dst, r.T_gt_est))
	{
		// Collinear (straight-line) run: rotation about the line is free; align
		// by the first poses instead.
		r.T_gt_est = G[0] * E[0].inverse();
	}
	double s2 = 0;
	for (size_t i = 0; i < n; i++)
	{
		const double e = (r.T_gt_est * E[i].translation() - G[i].translation()).norm();
		s2 += e * e;
		r.ate_mean += e;
		r.ate_max = std::max(r.ate_max, e);
	}
	r.ate_rmse = std::sqrt(s2 / n);
	r.ate_mean /= n;
	// RPE over consecutive pairs.
	double st = 0, sr = 0;
	for (size_t i = 1; i < n; i++)
	{
		const Eigen::Isometry3d dG = G[i - 1].inverse() * G[i], dE = E[i - 1].inverse() * E[i];
		const Eigen::Isometry3d D = dG.inverse() * dE;
		st += D.translation().squaredNorm();
		const double a = angleDeg(D.linear());
		sr += a * a;
	}
	r.rpe_trans_rmse = std::sqrt(st / (n - 1));
	r.rpe_rot_rmse_deg = std::sqrt(sr / (n - 1));
	// KITTI-style segments (devkit: every 10th start frame, first frame at >= start + length).
	std::vector<double> dist(n, 0.0);
	for (size_t i = 1; i < n; i++)
		dist[i] = dist[i - 1] + (G[i].translation() - G[i - 1].translation()).norm();
	r.path_length = dist.back();
	r.length_scale = std::min(1.0, r.path_length / 1000.0);
	double sumT = 0, sumR = 0;
	int cnt = 0;
	const size_t stepFrames = n >= 200 ? 10 : 1;
	for (int k = 1; k <= 8; k++)
	{
		TSegmentError seg;
		seg.length = 100.0 * k * r.length_scale;
		if (!(seg.length > 0)) continue;
		for (size_t i = 0; i < n; i += stepFrames)
		{
			const auto it = std::lower_bound(dist.begin() + i, dist.end(), dist[i] + seg.length);
			if (it == dist.end()) break;
			const size_t j = static_cast<size_t>(it - dist.begin());
			const Eigen::Isometry3d dG = G[i].inverse() * G[j], dE = E[i].inverse() * E[j];
			const Eigen::Isometry3d D = dE.inverse() * dG;
			seg.trans_pct += 100.0 * D.translation().norm() / seg.length;
			seg.rot_deg_per_m += angleDeg(D.linear()) / seg.length;
			seg.count++;
		}
		if (seg.count == 0) continue;
		sumT += seg.trans_pct;
		sumR += seg.rot_deg_per_m;
		cnt += seg.count;
		seg.trans_pct /= seg.count;
		seg.rot_deg_per_m /= seg.count;
		r.segments.push_back(seg);
	}
	if (cnt > 0)
	{
		r.kitti_trans_pct = sumT / cnt;
		r.kitti_rot_deg_per_m = sumR / cnt;
	}
	return r;
}

std::string TTrajectoryErrors::asText() const
{
	std::ostringstream o;
	o << std::fixed << std::setprecision(4);
	o << "matched poses:        " << matched << "\n"
	  << "path length:          " << path_length << " m\n"
	  << "ATE RMSE:             " << ate_rmse << " m (mean " << ate_mean << ", max " << ate_max
	  << ") after SE(3) alignment, no scale\n"
	  << "RPE (per step) RMSE:  " << rpe_trans_rmse << " m, " << rpe_rot_rmse_deg << " deg\n"
	  << "KITTI-style lengths:  100..800 m x " << length_scale
	  << (length_scale < 1 ? " (scaled down: run shorter than 1 km)" : "") << "\n";
	for (const auto& s : segments)
		o << "  length " << std::setw(9) << s.length << " m: " << std::setw(4) << s.count
		  << " segments, trans " << s.trans_pct << " %, rot " << s.rot_deg_per_m << " deg/m\n";
	o << "KITTI-style average:  trans " << kitti_trans_pct << " %, rot " << kitti_rot_deg_per_m
	  << " deg/m\n";
	return o.str();
}

}  // namespace shadyloc::eval
