/* ShadyLoc — the relative-pose estimator (stereo VO stage, reused by the localisers). */
#include <shadyloc/vo/RelativePoseEstimator.h>
#include <shadyloc/core/Units.h>

#include <chrono>
#include <stdexcept>

namespace shadyloc::vo
{
using Clock = std::chrono::steady_clock;

namespace
{
using core::msSince;
}  // namespace

std::string toString(RelativePoseStatus s)
{
	switch (s)
	{
		case RelativePoseStatus::Ok: return "ok";
		case RelativePoseStatus::FewInliers: return "few_inliers";
		case RelativePoseStatus::SolverFailed: return "solver_failed";
	}
	return "?";
}

RelativePoseEstimator::RelativePoseEstimator(const TOptions& o) : m_opts(o) {}

void RelativePoseEstimator::estimate(const TRelativePoseInput& in, TRelativePoseOutput& out) const
{
	if (!in.corr) throw std::invalid_argument("RelativePoseEstimator: input without correspondences");
	const auto& o = m_opts;
	const auto& corr = *in.corr;
	const auto& calib = in.calib;
	out = TRelativePoseOutput();

	// ---- RANSAC -------------------------------------------------------------------
	auto t0 = Clock::now();
	geometry::TRansacOptions ro;
	ro.inlier_threshold_px = o.ransac_threshold_px;
	ro.max_iterations = o.ransac_iterations;
	ro.seed = in.seed;
	// The motion model's prediction competes with the random minimal sets:
	// with only far landmarks (the invariant image outdoors) the inlier count
	// hardly changes along the viewing direction and random sets of noisy
	// far points can settle on a step twice too long (docs/vo.md).
	if (o.ransac_prediction && in.T_curr_ref_pred)
	{
		ro.hypotheses.push_back(*in.T_curr_ref_pred);
		ro.prior_sigma_m = o.ransac_prior_sigma_m * in.prior_sigma_scale;
	}
	ro.two_view_ba = o.two_view_ba;
	const auto rs = geometry::ransacStereoPose(calib, corr, ro);
	out.ransac_inliers = out.inliers = static_cast<size_t>(rs.inliers);
	out.inlier = rs.inlier;
	out.ms_ransac = msSince(t0);
	if (!rs.ok || rs.inliers < o.min_inliers)
	{
		out.status = RelativePoseStatus::FewInliers;
		return;
	}

	// ---- robust solve ---------------------------------------------------------------
	t0 = Clock::now();
	const auto solve = o.two_view_ba ? geometry::solveStereoPoseTwoView : geometry::solveStereoPose;
	geometry::TPoseSolverOptions so;
	so.sigma_px = o.sigma_px;
	so.sigma_disparity_px = o.sigma_disparity_px;
	so.huber_k = o.huber_k;
	auto sol = solve(calib, corr, rs.inlier, rs.T_curr_ref, so);
	if (sol.ok)
	{
		// Re-select inliers at the refined pose (RANSAC's minimal-set pose is
		// coarse) and solve once more on them.
		std::vector<uint8_t> in2(corr.size(), 0);
		int n = 0;
		for (size_t i = 0; i < corr.size(); i++)
		{
			Eigen::Vector3d r;
			in2[i] = geometry::stereoResidual(calib, sol.T_curr_ref, corr[i].P_ref, corr[i].z_curr, r) &&
					 r.norm() < o.ransac_threshold_px;
			n += in2[i];
		}
		if (n >= o.min_inliers)
		{
			const auto sol2 = solve(calib, corr, in2, sol.T_curr_ref, so);
			if (sol2.ok)
			{
				sol = sol2;
				out.inliers = static_cast<size_t>(n);
				out.inlier.swap(in2);
			}
		}
	}
	out.ms_solve = msSince(t0);
	if (!sol.ok)
	{
		out.status = RelativePoseStatus::SolverFailed;
		return;
	}
	out.status = RelativePoseStatus::Ok;
	out.T_curr_ref = sol.T_curr_ref;
	out.cov_T_ref_curr = sol.cov_T_ref_curr;
	out.rms_px = sol.rms_px;
}

}  // namespace shadyloc::vo
