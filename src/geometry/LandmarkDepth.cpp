/* ShadyLoc — a map landmark's depth from its re-observations (LandmarkDepth.h). */
#include <shadyloc/geometry/LandmarkDepth.h>

#include <Eigen/Cholesky>

#include <cmath>

namespace shadyloc::geometry
{
namespace
{
/** One stereo measurement of the landmark, whitened: r^T S^-1 r = |L^-1 r|^2. */
struct TWhitened
{
	Eigen::Isometry3d T_obs_kf;	 //!< identity: the keyframe's own pair
	Eigen::Vector3d z;
	Eigen::Matrix3d Linv;
	bool inlier = true;
};

/** Gauss-Newton on the landmark P in the keyframe, Huber-weighted; returns
 * false where it falls behind a camera. Sigma = the inverse information. */
bool solve(
	const TStereoCalib& calib, std::vector<TWhitened>& w, double huberK, Eigen::Vector3d& P, Eigen::Matrix3d& Sigma,
	double& chi2)
{
	for (int it = 0; it < 20; it++)
	{
		Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
		Eigen::Vector3d g = Eigen::Vector3d::Zero();
		chi2 = 0;
		for (const auto& x : w)
		{
			if (!x.inlier) continue;
			const Eigen::Vector3d Pobs = x.T_obs_kf * P;
			if (!(Pobs.z() > 1e-3)) return false;
			Eigen::Matrix3d Jp;
			const Eigen::Vector3d r = x.Linv * (calib.project(Pobs, &Jp) - x.z);
			const Eigen::Matrix3d J = x.Linv * Jp * x.T_obs_kf.linear();
			const double e = r.norm();
			const double wt = e <= huberK ? 1.0 : huberK / e;
			H += wt * J.transpose() * J;
			g += wt * J.transpose() * r;
			chi2 += e * e;
		}
		const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
		const Eigen::Vector3d step = -ldlt.solve(g);
		if (!step.allFinite()) return false;
		P += step;
		Sigma = ldlt.solve(Eigen::Matrix3d::Identity());
		if (!(P.z() > 1e-3)) return false;
		if (step.norm() < 1e-7 * P.norm()) break;
	}
	return Sigma.allFinite();
}
}  // namespace

TDepthRefinement refineDisparity(
	const TStereoCalib& calib, const Eigen::Vector3d& z_kf, const std::vector<TDepthObservation>& obs,
	const TDepthRefinementOptions& o)
{
	TDepthRefinement out;
	const double D0 = calib.disparity(z_kf.x(), z_kf.z());
	Eigen::Vector3d P0;
	if (static_cast<int>(obs.size()) < o.min_observations || !calib.triangulate(z_kf.x(), z_kf.y(), z_kf.z(), P0))
		return out;
	const double s2 = o.sigma_px * o.sigma_px;
	// The keyframe's own pair first (never left out), then each re-observation
	// with its pixel noise and its pose's. The landmark is solved in 3-D, so
	// the keyframe pixel's error, common to every re-observation, is not
	// averaged away; the disparity is read off at the end.
	std::vector<TWhitened> w;
	w.reserve(obs.size() + 1);
	w.push_back({Eigen::Isometry3d::Identity(), z_kf, Eigen::Matrix3d::Identity() / o.sigma_px});
	for (const auto& x : obs)
	{
		Eigen::Vector3d r;
		Matrix36d Jpose;
		if (!stereoResidual(calib, x.T_obs_kf, P0, x.z, r, &Jpose)) continue;
		const Eigen::Matrix3d S = o.reobservation_sigma_px * o.reobservation_sigma_px * Eigen::Matrix3d::Identity() +
								  Jpose * x.cov_T_obs_kf * Jpose.transpose();
		const Eigen::LLT<Eigen::Matrix3d> llt(S);
		if (llt.info() != Eigen::Success) continue;
		w.push_back({x.T_obs_kf, x.z, llt.matrixL().solve(Eigen::Matrix3d::Identity())});
	}
	Eigen::Vector3d P = P0;
	Eigen::Matrix3d Sigma;
	double chi2 = 0;
	if (!solve(calib, w, o.huber_k, P, Sigma, chi2)) return out;
	// Leave the disagreeing re-observations out and solve again.
	int used = 0;
	for (size_t i = 1; i < w.size(); i++)
	{
		auto& x = w[i];
		const Eigen::Vector3d r = x.Linv * (calib.project(x.T_obs_kf * P) - x.z);
		x.inlier = r.squaredNorm() <= o.outlier_chi2;
		used += x.inlier;
	}
	if (used < o.min_observations) return out;
	P = P0;
	if (!solve(calib, w, o.huber_k, P, Sigma, chi2)) return out;
	// D = fx b / Z: its variance from Z's.
	const double D = calib.fx * calib.baseline / P.z();
	const double dD_dZ = -D / P.z();
	if ((D - D0) * (D - D0) / (2 * s2) > o.stereo_chi2) return out;
	const double dof = 3.0 * (used + 1) - 3.0;
	out.ok = true;
	out.disparity = D;
	out.sigma_disparity = std::sqrt(std::max(1.0, chi2 / dof) * dD_dZ * dD_dZ * Sigma(2, 2));
	out.used = used;
	return out;
}

}  // namespace shadyloc::geometry
