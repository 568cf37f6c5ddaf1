/* ShadyLoc — stereo pose: 3-point RANSAC and robust Gauss-Newton. */
#include <shadyloc/geometry/PoseSolver.h>

#include "Skew.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace shadyloc::geometry
{
namespace
{
Eigen::Matrix3d expSO3(const Eigen::Vector3d& phi)
{
	const double a = phi.norm();
	if (a < 1e-12) return Eigen::Matrix3d::Identity() + skew(phi);
	return Eigen::AngleAxisd(a, phi / a).toRotationMatrix();
}
}  // namespace

Eigen::Isometry3d retractLeft(const Vector6d& xi, const Eigen::Isometry3d& T)
{
	const Eigen::Matrix3d dR = expSO3(xi.tail<3>());
	Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
	// Re-projected onto SO(3): a rotation that is orthonormal only to rounding
	// would grow away from it when fed back as the next start (a motion
	// prediction composed of earlier solutions), and Isometry3d::inverse()
	// assumes an exact rotation.
	out.linear() = Eigen::Quaterniond(dR * T.linear()).normalized().toRotationMatrix();
	out.translation() = dR * T.translation() + xi.head<3>();
	return out;
}

Matrix6d adjoint(const Eigen::Isometry3d& T)
{
	Matrix6d A = Matrix6d::Zero();
	const Eigen::Matrix3d R = T.linear();
	A.topLeftCorner<3, 3>() = R;
	A.topRightCorner<3, 3>() = skew(T.translation()) * R;
	A.bottomRightCorner<3, 3>() = R;
	return A;
}

Matrix6d invertCovariance(const Eigen::Isometry3d& T, const Matrix6d& covT)
{
	// (exp(xi) T)^-1 = T^-1 exp(-xi) = exp(-Ad_{T^-1} xi) T^-1
	const Matrix6d A = adjoint(T.inverse());
	return A * covT * A.transpose();
}

bool stereoResidual(
	const TStereoCalib& calib, const Eigen::Isometry3d& T_curr_ref, const Eigen::Vector3d& P_ref,
	const Eigen::Vector3d& z, Eigen::Vector3d& r, Matrix36d* J)
{
	const Eigen::Vector3d p = T_curr_ref * P_ref;
	if (!(p.z() > 1e-3)) return false;
	Eigen::Matrix3d Jp;
	r = calib.project(p, J ? &Jp : nullptr) - z;
	if (J)
	{
		J->leftCols<3>() = Jp;
		J->rightCols<3>() = -Jp * skew(p);
	}
	return true;
}

bool rigidTransform3D(
	const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
	Eigen::Isometry3d& T)
{
	const size_t n = src.size();
	if (n < 3 || dst.size() != n) return false;
	Eigen::Vector3d ms = Eigen::Vector3d::Zero(), md = Eigen::Vector3d::Zero();
	for (size_t i = 0; i < n; i++)
	{
		ms += src[i];
		md += dst[i];
	}
	ms /= double(n);
	md /= double(n);
	Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
	double spread = 0;
	for (size_t i = 0; i < n; i++)
	{
		S += (dst[i] - md) * (src[i] - ms).transpose();
		spread += (src[i] - ms).squaredNorm();
	}
	Eigen::JacobiSVD<Eigen::Matrix3d> svd(S, Eigen::ComputeFullU | Eigen::ComputeFullV);
	const Eigen::Vector3d sv = svd.singularValues();
	// Collinear points leave the rotation about their line undetermined.
	if (!(sv(1) > 1e-9 * std::max(1.0, sv(0))) || spread < 1e-12) return false;
	Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
	if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) D(2, 2) = -1;
	const Eigen::Matrix3d R = svd.matrixU() * D * svd.matrixV().transpose();
	T = Eigen::Isometry3d::Identity();
	T.linear() = R;
	T.translation() = md - R * ms;
	return true;
}

namespace
{
int countInliers(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const Eigen::Isometry3d& T,
	double thr, std::vector<uint8_t>* flags)
{
	int n = 0;
	const double thr2 = thr * thr;
	Eigen::Vector3d r;
	for (size_t i = 0; i < c.size(); i++)
	{
		const bool in = stereoResidual(calib, T, c[i].P_ref, c[i].z_curr, r) && r.squaredNorm() < thr2;
		if (flags) (*flags)[i] = in;
		n += in;
	}
	return n;
}
}  // namespace

TRansacResult ransacStereoPose(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const TRansacOptions& o)
{
	TRansacResult res;
	const int n = static_cast<int>(c.size());
	res.inlier.assign(c.size(), 0);
	if (n < 3) return res;
	std::mt19937 rng(o.seed);
	std::uniform_int_distribution<int> pick(0, n - 1);
	int best = -1;
	// The score: inliers, less the prior's penalty when one is given.
	double bestScore = -HUGE_VAL;
	auto score = [&](const Eigen::Isometry3d& T, int k) {
		if (!(o.prior_sigma_m > 0) || o.hypotheses.empty()) return double(k);
		const double d = (T.translation() - o.hypotheses.front().translation()).norm() / o.prior_sigma_m;
		return k - 0.5 * d * d;
	};
	Eigen::Isometry3d bestT = Eigen::Isometry3d::Identity();
	int maxIt = o.max_iterations;
	std::vector<Eigen::Vector3d> s(3), d(3);
	// Score a hypothesis; a new best is locally optimised (Chum et al.,
	// LO-RANSAC, DAGM 2003: a minimal 3D-3D set is noisy, far points' depths
	// are poor) on the image residuals of its inliers (Gauss-Newton, or the
	// two-view bundle adjustment with two_view_ba).
	// f: the inliers of the hypothesis being considered, f2 of its refinement.
	std::vector<uint8_t> f(c.size(), 0), f2(c.size(), 0);
	auto consider = [&](Eigen::Isometry3d T, int it) {
		int k = countInliers(calib, c, T, o.inlier_threshold_px, &f);
		if (score(T, k) > bestScore && k >= 6)
		{
			for (int lo = 0; lo < 2; lo++)
			{
				TPoseSolverOptions so;
				so.max_iterations = 4;
				so.sigma_px = 1.0;
				so.covariance = false;
				const auto sol = o.two_view_ba ? solveStereoPoseTwoView(calib, c, f, T, so)
												: solveStereoPose(calib, c, f, T, so);
				if (!sol.ok) break;
				const int k2 = countInliers(calib, c, sol.T_curr_ref, o.inlier_threshold_px, &f2);
				if (score(sol.T_curr_ref, k2) <= score(T, k)) break;
				k = k2;
				T = sol.T_curr_ref;
				f.swap(f2);
			}
		}
		if (score(T, k) <= bestScore) return;
		bestScore = score(T, k);
		best = k;
		bestT = T;
		// Adaptive bound: iterations for `confidence` of one all-inlier sample.
		const double w = double(k) / n;
		const double p3 = w * w * w;
		if (p3 > 1e-9 && p3 < 1.0)
		{
			const double need = std::log(1 - o.confidence) / std::log(1 - p3);
			maxIt = std::min(o.max_iterations, static_cast<int>(std::ceil(need)) + 1);
		}
		else if (p3 >= 1.0)
			maxIt = std::min(maxIt, it + 1);
	};
	// Given hypotheses first: along the viewing direction a far-field-only
	// scene constrains the motion weakly, and random minimal sets of noisy
	// far points can miss the right pose that a motion prediction starts near.
	for (const auto& T : o.hypotheses) consider(T, 0);
	for (int it = 0; it < maxIt; it++)
	{
		res.iterations = it + 1;
		int i0 = pick(rng), i1 = pick(rng), i2 = pick(rng);
		if (i0 == i1 || i0 == i2 || i1 == i2) continue;
		s = {c[i0].P_ref, c[i1].P_ref, c[i2].P_ref};
		d = {c[i0].P_curr, c[i1].P_curr, c[i2].P_curr};
		Eigen::Isometry3d T;
		if (!rigidTransform3D(s, d, T)) continue;
		consider(T, it);
	}
	if (best < 3) return res;
	std::vector<uint8_t> flags(c.size(), 0);
	countInliers(calib, c, bestT, o.inlier_threshold_px, &flags);
	// Refit on all inliers (least squares in 3D), keep it if it does not lose inliers.
	s.clear();
	d.clear();
	for (int i = 0; i < n; i++)
		if (flags[i])
		{
			s.push_back(c[i].P_ref);
			d.push_back(c[i].P_curr);
		}
	Eigen::Isometry3d T;
	if (rigidTransform3D(s, d, T))
	{
		std::vector<uint8_t> f2(c.size(), 0);
		if (countInliers(calib, c, T, o.inlier_threshold_px, &f2) >= best)
		{
			bestT = T;
			flags.swap(f2);
		}
	}
	res.T_curr_ref = bestT;
	res.inlier = flags;
	res.inliers = static_cast<int>(std::count(flags.begin(), flags.end(), 1));
	res.ok = res.inliers >= 3;
	return res;
}

Eigen::Vector3d measurementVariances(const TPoseSolverOptions& o)
{
	const double s2 = o.sigma_px * o.sigma_px;
	return {s2, s2, s2 + o.sigma_disparity_px * o.sigma_disparity_px};
}

namespace
{
/** The residual r and Jacobian J of a correspondence at T, and W, the
 * inverse of r's covariance (pixel noise plus the landmark's, seen through
 * the projection); false when it does not project. */
bool whitenedLinearisation(
	const TStereoCalib& calib, const Eigen::Isometry3d& T, const TStereoCorrespondence& c, const TPoseSolverOptions& o,
	Eigen::Vector3d& r, Matrix36d& J, Eigen::Matrix3d& W)
{
	if (!stereoResidual(calib, T, c.P_ref, c.z_curr, r, &J)) return false;
	Eigen::Matrix3d S = measurementVariances(o).asDiagonal();
	if (o.use_landmark_covariance)
	{
		const Eigen::Matrix3d JP = J.leftCols<3>() * T.linear();  // d r / d P_ref
		S += JP * c.cov_ref * JP.transpose();
	}
	W = S.inverse();
	return true;
}

/** Huber IRLS weight of a residual of whitened norm sqrt(r^T W r). */
double huberWeight(const Eigen::Vector3d& r, const Eigen::Matrix3d& W, double k)
{
	const double e = std::sqrt(std::max(0.0, r.dot(W * r)));
	return e <= k ? 1.0 : k / e;
}

/** One correspondence's robust normal-equation terms at T (Huber IRLS
 * weight); false when it does not project. */
bool normalTerms(
	const TStereoCalib& calib, const Eigen::Isometry3d& T, const TStereoCorrespondence& c, const TPoseSolverOptions& o,
	Matrix6d& H, Vector6d& g, double& sqNorm)
{
	Eigen::Vector3d r;
	Matrix36d J;
	Eigen::Matrix3d W;
	if (!whitenedLinearisation(calib, T, c, o, r, J, W)) return false;
	const double w = huberWeight(r, W, o.huber_k);
	const Eigen::Matrix<double, 6, 3> JtW = w * J.transpose() * W;
	H.noalias() = JtW * J;
	g.noalias() = JtW * r;
	sqNorm = r.squaredNorm();
	return true;
}
}  // namespace

namespace
{
/** Robust Gauss-Newton from T_init; accumulate(T, iteration, H, g, sumSq,
 * used) adds the normal-equation terms at T. */
template <class Accumulate>
TPoseSolution gaussNewton(const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o, Accumulate&& accumulate)
{
	TPoseSolution sol;
	Eigen::Isometry3d T = T_init;
	Matrix6d H = Matrix6d::Zero();
	double sumSq = 0;
	int used = 0;
	for (int it = 0; it <= o.max_iterations; it++)
	{
		H.setZero();
		Vector6d g = Vector6d::Zero();
		sumSq = 0;
		used = 0;
		// The last linearisation serves the covariance only.
		if (it == o.max_iterations && !o.covariance) break;
		accumulate(T, it, H, g, sumSq, used);
		if (used < 3) return sol;
		if (it == o.max_iterations) break;
		const Vector6d dx = H.ldlt().solve(-g);
		if (!dx.allFinite()) return sol;
		T = retractLeft(dx, T);
		sol.iterations = it + 1;
		if (dx.norm() < o.convergence) break;
	}
	if (!o.covariance)
	{
		sol.T_curr_ref = T;
		sol.ok = true;
		return sol;
	}
	// H is from the last linearisation (at the final T, or one step of size < convergence before it).
	Eigen::FullPivLU<Matrix6d> lu(H);
	if (!lu.isInvertible()) return sol;
	const Matrix6d covCurrRef = lu.inverse();
	sol.T_curr_ref = T;
	sol.cov_T_ref_curr = invertCovariance(T, covCurrRef);
	sol.rms_px = std::sqrt(sumSq / std::max(1, used) / 3.0);
	sol.ok = sol.cov_T_ref_curr.allFinite();
	return sol;
}
}  // namespace

TPoseSolution solveStereoPose(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c,
	const std::vector<uint8_t>& use, const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o)
{
	return gaussNewton(T_init, o, [&](const Eigen::Isometry3d& T, int, Matrix6d& H, Vector6d& g, double& sumSq, int& used) {
		for (size_t i = 0; i < c.size(); i++)
		{
			if (!use.empty() && !use[i]) continue;
			Matrix6d Hi;
			Vector6d gi;
			double sq;
			if (!normalTerms(calib, T, c[i], o, Hi, gi, sq)) continue;
			H += Hi;
			g += gi;
			sumSq += sq;
			used++;
		}
	});
}

std::vector<TNormalTerms> normalTermsAt(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const Eigen::Isometry3d& T,
	const TPoseSolverOptions& o)
{
	std::vector<TNormalTerms> out(c.size());
	for (size_t i = 0; i < c.size(); i++) out[i].ok = normalTerms(calib, T, c[i], o, out[i].H, out[i].g, out[i].sq);
	return out;
}

TPoseSolution solveStereoPoseCounted(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const std::vector<int>& count,
	const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o, const std::vector<TNormalTerms>* atInit)
{
	if (count.size() != c.size() || (atInit && atInit->size() != c.size()))
		throw std::invalid_argument("solveStereoPoseCounted: count or atInit not one per correspondence");
	TNormalTerms t;
	return gaussNewton(T_init, o, [&](const Eigen::Isometry3d& T, int it, Matrix6d& H, Vector6d& g, double& sumSq, int& used) {
		for (size_t i = 0; i < c.size(); i++)
		{
			if (count[i] <= 0) continue;
			const bool cached = it == 0 && atInit;
			if (!cached) t.ok = normalTerms(calib, T, c[i], o, t.H, t.g, t.sq);
			const TNormalTerms& ti = cached ? (*atInit)[i] : t;
			if (!ti.ok) continue;
			H += double(count[i]) * ti.H;
			g += double(count[i]) * ti.g;
			sumSq += count[i] * ti.sq;
			used += count[i];
		}
	});
}

std::vector<TFrozenTerms> frozenTermsAt(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const Eigen::Isometry3d& T,
	const TPoseSolverOptions& o)
{
	std::vector<TFrozenTerms> out(c.size());
	Eigen::Vector3d r;
	Matrix36d J;
	for (size_t i = 0; i < c.size(); i++)
	{
		auto& f = out[i];
		f.ok = whitenedLinearisation(calib, T, c[i], o, r, J, f.W);
		if (!f.ok) continue;
		f.JtW.noalias() = J.transpose() * f.W;
		f.JtWJ.noalias() = f.JtW * J;
	}
	return out;
}

TPoseSolution solveStereoPoseCountedChord(
	const TStereoCalib& calib, const std::vector<TStereoCorrespondence>& c, const std::vector<int>& count,
	const Eigen::Isometry3d& T_init, const TPoseSolverOptions& o, const std::vector<TFrozenTerms>& at)
{
	if (count.size() != c.size() || at.size() != c.size())
		throw std::invalid_argument("solveStereoPoseCountedChord: count or at not one per correspondence");
	if (o.covariance) throw std::invalid_argument("solveStereoPoseCountedChord: gives no covariance (o.covariance)");
	return gaussNewton(T_init, o, [&](const Eigen::Isometry3d& T, int, Matrix6d& H, Vector6d& g, double&, int& used) {
		Eigen::Vector3d r;
		for (size_t i = 0; i < c.size(); i++)
		{
			if (count[i] <= 0 || !at[i].ok || !stereoResidual(calib, T, c[i].P_ref, c[i].z_curr, r)) continue;
			const double cw = count[i] * huberWeight(r, at[i].W, o.huber_k);
			H.noalias() += cw * at[i].JtWJ;
			g.noalias() += cw * (at[i].JtW * r);
			used += count[i];
		}
	});
}

}  // namespace shadyloc::geometry
