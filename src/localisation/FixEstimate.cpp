/* ShadyLoc — the estimate and accept stages every localiser shares (FixEstimate.h). */
#include <shadyloc/localisation/FixEstimate.h>
#include <shadyloc/core/Units.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <future>
#include <limits>
#include <optional>
#include <random>

namespace shadyloc::localisation
{
using geometry::Matrix6d;
using geometry::TPoseWithCov;
using geometry::Vector6d;
using core::kDeg;

geometry::TPoseSolverOptions solverOptionsFor(const TLocaliserOptions& o)
{
	geometry::TPoseSolverOptions so;
	so.sigma_px = o.sigma_px;
	so.sigma_disparity_px = o.sigma_disparity_px;
	so.huber_k = o.huber_k;
	return so;
}

namespace
{
/** A posteriori variance factor of a solve (Foerstner and Wrobel,
 * "Photogrammetric Computer Vision", 2016, Sec. 4.2.3): the inliers' squared
 * residuals whitened by their a priori covariance (pixel noise plus the map
 * landmark's covariance through the projection, the model of
 * geometry::solveStereoPose), over the redundancy 3n - 6. About 1 when the
 * a priori noise is right; larger when the channel's measurements are
 * noisier than sigma_px says (the invariant image) or the landmarks fit the
 * pose worse than their covariance allows. */
double varianceFactor(
	const geometry::TStereoCalib& calib, const std::vector<geometry::TStereoCorrespondence>& corr,
	const std::vector<uint8_t>& inlier, const Eigen::Isometry3d& T_curr_ref, const geometry::TPoseSolverOptions& so)
{
	double sum = 0;
	int n = 0;
	for (size_t i = 0; i < corr.size(); i++)
	{
		if (i < inlier.size() && !inlier[i]) continue;
		Eigen::Vector3d r;
		geometry::Matrix36d J;
		if (!geometry::stereoResidual(calib, T_curr_ref, corr[i].P_ref, corr[i].z_curr, r, &J)) continue;
		const Eigen::Matrix3d JP = J.leftCols<3>() * T_curr_ref.linear();
		const Eigen::Matrix3d S =
			Eigen::Matrix3d(geometry::measurementVariances(so).asDiagonal()) + JP * corr[i].cov_ref * JP.transpose();
		sum += r.dot(S.ldlt().solve(r));
		n++;
	}
	return n > 2 ? sum / (3.0 * n - 6.0) : std::numeric_limits<double>::infinity();
}

/** Bootstrap covariance of T_ref_curr (left perturbation) around the solve
 * T_curr_ref: the inliers resampled with replacement `samples` times, each
 * resample solved from T_curr_ref (fixed landmarks with their covariance,
 * geometry::solveStereoPose), the spread of the solutions about T_curr_ref
 * (Efron and Tibshirani, "An Introduction to the Bootstrap", 1993, ch. 6).
 * It sees what the information matrix cannot: a pose that rests on a few
 * correspondences (a wrong match among the inliers, landmarks all far or on
 * one side) moves when they are left out. Zero when fewer than 2 resamples
 * solve. Each resample is solved, not stepped once from the solution: a
 * one-step bootstrap (terms linearised once, Huber weights kept) is far
 * cheaper but came out too small on the marginal solves that matter, and
 * doubled the false fixes on the 301 m set (docs/localisation.md). */
Matrix6d bootstrapCovariance(
	const geometry::TStereoCalib& calib, const std::vector<geometry::TStereoCorrespondence>& corr,
	const std::vector<uint8_t>& inlier, const Eigen::Isometry3d& T_curr_ref, const TLocaliserOptions& o, uint32_t seed,
	int threads)
{
	std::vector<geometry::TStereoCorrespondence> in;
	for (size_t i = 0; i < corr.size(); i++)
		if (i >= inlier.size() || inlier[i]) in.push_back(corr[i]);
	if (in.size() < 4 || o.bootstrap_samples < 2) return Matrix6d::Zero();
	// The resamples are drawn in one sequence whatever the threads, so the
	// covariance is the same to the bit with one thread or two.
	const size_t samples = static_cast<size_t>(o.bootstrap_samples);
	std::mt19937 rng(seed);
	std::uniform_int_distribution<size_t> pick(0, in.size() - 1);
	std::vector<std::vector<int>> counts(samples, std::vector<int>(in.size(), 0));
	for (auto& count : counts)
		for (size_t k = 0; k < in.size(); k++) count[pick(rng)]++;
	geometry::TPoseSolverOptions so = solverOptionsFor(o);
	so.max_iterations = 5;
	so.covariance = false;	// a resample's pose is all the spread needs
	const Eigen::Isometry3d T_ref_curr = T_curr_ref.inverse();
	// Every resample starts at the solve: its first linearisation is shared,
	// and a resample is a count per inlier rather than a copied list.
	std::vector<geometry::TNormalTerms> atSolve;
	std::vector<geometry::TFrozenTerms> frozen;
	if (o.bootstrap_relinearise)
		atSolve = geometry::normalTermsAt(calib, in, T_curr_ref, so);
	else
		frozen = geometry::frozenTermsAt(calib, in, T_curr_ref, so);
	std::vector<std::optional<Vector6d>> xi(samples);
	auto solveRange = [&](size_t b0, size_t b1) {
		for (size_t b = b0; b < b1; b++)
		{
			const auto sol =
				o.bootstrap_relinearise
					? geometry::solveStereoPoseCounted(calib, in, counts[b], T_curr_ref, so, &atSolve)
					: geometry::solveStereoPoseCountedChord(calib, in, counts[b], T_curr_ref, so, frozen);
			if (sol.ok) xi[b] = geometry::localLeft(sol.T_curr_ref.inverse(), T_ref_curr);
		}
	};
	if (threads >= 2)
	{
		auto half = std::async(std::launch::async, solveRange, samples / 2, samples);
		solveRange(0, samples / 2);
		half.get();
	}
	else
		solveRange(0, samples);
	// Summed in resample order: the same sum whatever the threads.
	Matrix6d C = Matrix6d::Zero();
	int solved = 0;
	for (const auto& x : xi)
		if (x)
		{
			C += *x * x->transpose();
			solved++;
		}
	return solved >= 2 ? Matrix6d(C / (solved - 1)) : Matrix6d::Zero();
}

/** The smallest covariance at least as large as both A and B in the
 * directions where each is larger (A's whitening, B's eigenvalues in it
 * clamped to >= 1); A when B is zero. B is a sample covariance of `samples`
 * draws: in A's whitening, when A is right, its eigenvalues scatter up to
 * the Marchenko-Pastur edge (1 + sqrt(6 / (samples - 1)))^2 (about 2 for 30
 * draws) by chance alone, so eigenvalues below the edge are taken as 1 (no
 * evidence that A is too small there). */
Matrix6d covarianceMax(const Matrix6d& A, const Matrix6d& B, int samples)
{
	const Eigen::LLT<Matrix6d> llt(0.5 * (A + A.transpose()));
	if (llt.info() != Eigen::Success) return A + B;
	const Matrix6d L = llt.matrixL();
	const Matrix6d Li = L.inverse();
	const Matrix6d M = Li * (0.5 * (B + B.transpose())) * Li.transpose();
	Eigen::SelfAdjointEigenSolver<Matrix6d> es(M);
	const double edge = std::pow(1.0 + std::sqrt(6.0 / std::max(1, samples - 1)), 2);
	Vector6d d = es.eigenvalues();
	for (int i = 0; i < 6; i++) d[i] = d[i] > edge ? d[i] : 1.0;
	return L * es.eigenvectors() * d.asDiagonal() * es.eigenvectors().transpose() * L.transpose();
}



LocaliserStatus statusOf(AcceptanceVerdict v)
{
	switch (v)
	{
		case AcceptanceVerdict::Fix: return LocaliserStatus::Ok;
		case AcceptanceVerdict::Unconfirmed: return LocaliserStatus::Unconfirmed;
		case AcceptanceVerdict::Uncounted: return LocaliserStatus::Uncertain;
		case AcceptanceVerdict::PredictionInconsistent: return LocaliserStatus::PredictionInconsistent;
		case AcceptanceVerdict::MotionInconsistent: return LocaliserStatus::MotionInconsistent;
	}
	return LocaliserStatus::SolverFailed;
}
}  // namespace

Matrix6d fixCovariance(const Matrix6d& solver, const Matrix6d& bootstrap, double cov_scale, int samples)
{
	const Matrix6d scaled = cov_scale * solver;
	if (samples < 2 || bootstrap.isZero(0)) return scaled;
	return covarianceMax(scaled, bootstrap, samples);
}

Matrix6d solveCovariance(
	const TLocaliserOptions& o, const geometry::TStereoCalib& calib,
	const std::vector<geometry::TStereoCorrespondence>& corr, const vo::TRelativePoseOutput& po, uint32_t seed,
	int threads)
{
	return fixCovariance(
		po.cov_T_ref_curr,
		o.bootstrap_samples > 0 ? bootstrapCovariance(calib, corr, po.inlier, po.T_curr_ref, o, seed, threads)
								: Matrix6d::Zero(),
		o.cov_scale, o.bootstrap_samples);
}

bool withinFixBounds(const TLocaliserOptions& o, const Matrix6d& cov)
{
	return !(o.max_sigma_m > 0 && translationSigma(cov) > o.max_sigma_m) &&
		   !(o.max_sigma_deg > 0 && rotationSigma(cov) > o.max_sigma_deg * kDeg);
}

void describeSolve(
	const TLocaliserOptions& o, const geometry::TStereoCalib& calib,
	const std::vector<geometry::TStereoCorrespondence>& corr, const vo::TRelativePoseOutput& po, size_t frame,
	TLocaliserResult& r, int threads)
{
	r.solved = true;
	r.var_factor = varianceFactor(calib, corr, po.inlier, po.T_curr_ref, solverOptionsFor(o));
	r.T_kf_live = po.T_curr_ref.inverse();
	const uint32_t seed = static_cast<uint32_t>(frame * 2654435761u + 7) ^ 0x9e3779b9u;
	r.cov = solveCovariance(o, calib, corr, po, seed, threads);
	r.sigma_m = translationSigma(r.cov);
	r.sigma_deg = rotationSigma(r.cov) / kDeg;
}

void acceptSolve(
	FixAcceptance& accept, const TLocaliserOptions& o, const TLocaliserInput& in, const KeyframeLink& link,
	TLocaliserResult& r)
{
	const bool uncertain = !withinFixBounds(o, r.cov);
	if (uncertain && o.uncertain_breaks_chain)
	{
		r.status = LocaliserStatus::Uncertain;
		accept.noSolve();
		r.consistent = 0;
		return;
	}
	TSolve sv;
	sv.frame = in.frame;
	sv.pose = r.pose();
	const TAcceptance acc = accept.judge(sv, in.prediction, in.motion, in.track_confirmed, !uncertain, link);
	r.prediction_d2 = acc.prediction_d2;
	r.motion_d2 = acc.motion_d2;
	r.consistent = acc.consistent;
	r.status = statusOf(acc.verdict);
}

TPoseWithCov keyframeLink(const CKeyframeMap& map, const TLocaliserOptions& o, uint32_t a, uint32_t b)
{
	TPoseWithCov r;
	if (a == b) return r;
	if (const auto rp = map.measuredRelativePose(a, b))
	{
		r.T = rp->T_a_b;
		r.cov = rp->cov;
		return r;
	}
	if (map.frameOf(a) != map.frameOf(b))
	{
		// Experiences in frames of their own: nothing relates them, so no
		// test across them can pass (an infinite covariance).
		r.cov.setConstant(std::numeric_limits<double>::infinity());
		return r;
	}
	// Across a VO break: the map poses (one of them only predicted), with a
	// covariance that says so.
	r.T = map.keyframe(a).T_map_kf.inverse() * map.keyframe(b).T_map_kf;
	const double st = o.cross_segment_sigma_m, sr = o.cross_segment_sigma_deg * kDeg;
	r.cov.diagonal() << st * st, st * st, st * st, sr * sr, sr * sr, sr * sr;
	return r;
}

bool intoReference(
	geometry::TStereoCorrespondence& corr, const Eigen::Isometry3d& T_ref_k, const geometry::TStereoCalib& calibKf)
{
	corr.P_ref = T_ref_k * corr.P_ref;
	corr.cov_ref = T_ref_k.linear() * corr.cov_ref * T_ref_k.linear().transpose();
	if (!(corr.P_ref.z() > 0.5)) return false;
	// A refined disparity's sigma follows the depth: D ~ 1/Z, so sigma_D ~ D^2
	// (along nearly parallel rays: keyframes a window apart).
	const double D0 = corr.calib_ref.disparity(corr.z_ref.x(), corr.z_ref.z());
	corr.z_ref = calibKf.project(corr.P_ref);
	const double D1 = calibKf.disparity(corr.z_ref.x(), corr.z_ref.z());
	if (corr.sigma_disparity_ref > 0) corr.sigma_disparity_ref *= (D1 / D0) * (D1 / D0);
	corr.calib_ref = calibKf;
	return true;
}

}  // namespace shadyloc::localisation
