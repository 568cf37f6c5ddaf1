/* ShadyLoc — two-view stereo bundle adjustment of a relative pose.
 *
 * The one-view solve (solveStereoPose) keeps the reference landmarks fixed
 * and folds their uncertainty into each residual's covariance, linearised at
 * the current pose. For far landmarks (disparity of a few pixels) that
 * linearisation is poor, and because the folded covariance grows as the pose
 * moves towards the landmarks, the weighted cost can be lowered by moving
 * forward: with only far landmarks (the invariant image of an outdoor scene)
 * single steps came out up to twice too long. Here the landmarks are unknowns
 * too: each has its stereo measurement in the reference frame and in the
 * current one, both with pixel noise, and the landmarks are eliminated by the
 * Schur complement (Triggs et al., "Bundle Adjustment — A Modern Synthesis",
 * 2000; Hartley & Zisserman, 2nd ed., A6.3), so the cost is the exact
 * reprojection error of both views, minimised by Levenberg-Marquardt.
 */
#include <shadyloc/geometry/PoseSolver.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace shadyloc::geometry
{
namespace
{
struct TLandmarkBlock
{
	int idx;  //!< correspondence index
	Eigen::Vector3d z_ref;	//!< the landmark's stereo measurement in the reference frame [px]
	const TStereoCalib* calib_ref;	//!< the reference frame's calibration
	/** Information of z_ref where its disparity was refined by other views
	 * (sigma_disparity_ref > 0); otherwise the pixel noise model below. */
	std::optional<Eigen::Matrix3d> W_ref;
	// Normal-equation blocks at the last linearisation:
	Eigen::Matrix<double, 6, 3> Hpx = Eigen::Matrix<double, 6, 3>::Zero();  //!< pose-landmark
	Eigen::Matrix3d Hxx = Eigen::Matrix3d::Zero();	//!< landmark-landmark
	Eigen::Vector3d gx = Eigen::Vector3d::Zero();  //!< landmark gradient
};

double huberCost(double e, double k) { return e <= k ? e * e : 2 * k * e - k * k; }
double huberWeight(double e, double k) { return e <= k ? 1.0 : k / e; }
}  // namespace

TPoseSolution solveStereoPoseTwoView(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c,
	const std::vector<uint8_t>& use, const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o)
{
	TPoseSolution sol;
	const double sinv = 1.0 / o.sigma_px, s2inv = sinv * sinv;
	// uR weighs less by uRcut of its sigma_px weight where the disparity is
	// noisier (sigma_disparity_px); written as a correction so that without
	// it every sum is the isotropic one, to the bit.
	const Eigen::Vector3d var = measurementVariances(o);
	const double uRcut = 1.0 - var(0) / var(2);
	const auto whitenedNorm = [&](const Eigen::Vector3d& r) {
		return std::sqrt(r.squaredNorm() - uRcut * r(2) * r(2)) * sinv;
	};
	// w A^T diag(1, 1, 1 - uRcut) B (w: Huber weight / sigma_px^2).
	const auto weighted = [&](double w, const auto& A, const auto& B) {
		auto out = (w * A.transpose() * B).eval();
		if (uRcut > 0) out -= (w * uRcut) * A.row(2).transpose() * B.row(2);
		return out;
	};
	std::vector<TLandmarkBlock> L;
	L.reserve(c.size());
	for (size_t i = 0; i < c.size(); i++)
	{
		if (!use.empty() && !use[i]) continue;
		// The reference frame's own measurement and calibration: a map's
		// keyframe may have been made with another camera than the live one.
		if (!c[i].hasReferenceObservation())
			throw std::invalid_argument(
				"solveStereoPoseTwoView: correspondence " + std::to_string(i) +
				" has no reference observation (z_ref)");
		// Behind either camera at the start: no projection to adjust.
		if (!(c[i].P_ref.z() > 1e-3) || !((T_init * c[i].P_ref).z() > 1e-3)) continue;
		TLandmarkBlock b;
		b.idx = static_cast<int>(i);
		b.z_ref = c[i].z_ref;
		b.calib_ref = &c[i].calib_ref;
		if (c[i].sigma_disparity_ref > 0)
			b.W_ref = TStereoCalib::measurementCovariance(o.sigma_px, c[i].sigma_disparity_ref).inverse();
		L.push_back(b);
	}
	if (L.size() < 3) return sol;

	// Robust cost of a pose and landmark set (whitened residual norms, Huber).
	// The reference term's whitened norm and weighted products: a refined
	// landmark's by its own information, every other by the pixel model.
	const auto refNorm = [&](const TLandmarkBlock& b, const Eigen::Vector3d& r) {
		return b.W_ref ? std::sqrt(r.dot(*b.W_ref * r)) : whitenedNorm(r);
	};
	const auto refWeighted = [&](const TLandmarkBlock& b, double hw, const auto& A, const auto& B) {
		return b.W_ref ? (hw * A.transpose() * *b.W_ref * B).eval() : weighted(hw * s2inv, A, B);
	};
	auto cost = [&](const Eigen::Isometry3d& T, const std::vector<Eigen::Vector3d>& X, double* sumSqCurr,
					int* usedCurr) {
		double f = 0, ss = 0;
		int n = 0;
		for (size_t k = 0; k < L.size(); k++)
		{
			if (!(X[k].z() > 1e-3)) return HUGE_VAL;
			const Eigen::Vector3d rr = L[k].calib_ref->project(X[k]) - L[k].z_ref;
			f += huberCost(refNorm(L[k], rr), o.huber_k);
			Eigen::Vector3d r;
			if (!stereoResidual(calib, T, X[k], c[L[k].idx].z_curr, r)) return HUGE_VAL;
			f += huberCost(whitenedNorm(r), o.huber_k);
			ss += r.squaredNorm();
			n++;
		}
		if (sumSqCurr) *sumSqCurr = ss;
		if (usedCurr) *usedCurr = n;
		return f;
	};

	Eigen::Isometry3d T = T_init;
	std::vector<Eigen::Vector3d> X(L.size()), Xnew(L.size());
	for (size_t k = 0; k < L.size(); k++) X[k] = c[L[k].idx].P_ref;
	double f = cost(T, X, nullptr, nullptr);
	if (!std::isfinite(f)) return sol;
	// Normal equations at (T, X) with IRLS weights; the landmark blocks are
	// kept for the Schur complement.
	Matrix6d Hpp;
	Vector6d gp;
	auto linearise = [&]() {
		Hpp.setZero();
		gp.setZero();
		for (size_t k = 0; k < L.size(); k++)
		{
			auto& b = L[k];
			Eigen::Matrix3d Jk;
			const Eigen::Vector3d rk = b.calib_ref->project(X[k], &Jk) - b.z_ref;
			Eigen::Vector3d rc;
			Matrix36d Jc;
			stereoResidual(calib, T, X[k], c[b.idx].z_curr, rc, &Jc);
			const Eigen::Matrix3d JcX = Jc.leftCols<3>() * T.linear();
			const double hk = huberWeight(refNorm(b, rk), o.huber_k);
			const double wc = huberWeight(whitenedNorm(rc), o.huber_k) * s2inv;
			Hpp += weighted(wc, Jc, Jc);
			gp += weighted(wc, Jc, rc);
			b.Hpx = weighted(wc, Jc, JcX);
			b.Hxx = refWeighted(b, hk, Jk, Jk) + weighted(wc, JcX, JcX);
			b.gx = refWeighted(b, hk, Jk, rk) + weighted(wc, JcX, rc);
		}
	};
	// Schur complement with Levenberg-Marquardt damping (1 + lambda) on the
	// diagonals: eliminates every landmark (3x3 blocks).
	std::vector<Eigen::Matrix3d> HxxInv(L.size());
	auto reduce = [&](double lambda, Matrix6d& A, Vector6d& bvec) {
		A = Hpp;
		A.diagonal() *= 1 + lambda;
		bvec = gp;
		for (size_t k = 0; k < L.size(); k++)
		{
			Eigen::Matrix3d H = L[k].Hxx;
			H.diagonal() *= 1 + lambda;
			HxxInv[k] = H.inverse();
			A -= L[k].Hpx * HxxInv[k] * L[k].Hpx.transpose();
			bvec -= L[k].Hpx * HxxInv[k] * L[k].gx;
		}
	};

	double lambda = 1e-4;
	for (int it = 0; it < o.max_iterations; it++)
	{
		linearise();
		bool accepted = false;
		Vector6d dxi = Vector6d::Zero();
		for (int tries = 0; tries < 10 && !accepted; tries++)
		{
			Matrix6d A;
			Vector6d bvec;
			reduce(lambda, A, bvec);
			dxi = A.ldlt().solve(-bvec);
			if (!dxi.allFinite()) return sol;
			for (size_t k = 0; k < L.size(); k++)
				Xnew[k] = X[k] + HxxInv[k] * (-L[k].gx - L[k].Hpx.transpose() * dxi);
			const Eigen::Isometry3d Tn = retractLeft(dxi, T);
			const double fn = cost(Tn, Xnew, nullptr, nullptr);
			if (fn < f)
			{
				T = Tn;
				X.swap(Xnew);
				f = fn;
				lambda = std::max(1e-7, lambda * 0.1);
				accepted = true;
			}
			else
				lambda *= 10;
		}
		sol.iterations = it + 1;
		if (!accepted || dxi.norm() < o.convergence) break;
	}
	if (!o.covariance)
	{
		sol.T_curr_ref = T;
		sol.ok = true;
		return sol;
	}
	// Covariance of the pose: inverse of its marginal information (the
	// undamped Schur complement at the solution).
	linearise();
	Matrix6d A;
	Vector6d bvec;
	reduce(0.0, A, bvec);
	Eigen::FullPivLU<Matrix6d> lu(A);
	if (!lu.isInvertible()) return sol;
	double sumSq = 0;
	int used = 0;
	cost(T, X, &sumSq, &used);
	sol.T_curr_ref = T;
	sol.cov_T_ref_curr = invertCovariance(T, lu.inverse());
	sol.rms_px = std::sqrt(sumSq / std::max(1, used) / 3.0);
	sol.ok = sol.cov_T_ref_curr.allFinite();
	return sol;
}

}  // namespace shadyloc::geometry
