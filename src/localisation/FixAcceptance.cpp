/* ShadyLoc — the accept stage of a localiser (see FixAcceptance.h). */
#include <shadyloc/localisation/FixAcceptance.h>

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <limits>

namespace shadyloc::localisation
{
using geometry::Matrix6d;
using geometry::TPoseWithCov;
using geometry::Vector6d;

double predictionDistance2(const TKeyframePose& solve, const TKeyframePose& pred, const KeyframeLink& link)
{
	const TPoseWithCov p = pred.kf == solve.kf ? pred.withCov() : geometry::compose(link(solve.kf, pred.kf), pred.withCov());
	return mahalanobis2(geometry::localLeft(solve.T_kf_live, p.T), p.cov + solve.cov);
}

TPoseWithCov fuseWithPrediction(const TPoseWithCov& solve, const TPoseWithCov& prediction)
{
	const Matrix6d& P = prediction.cov;
	const Eigen::LDLT<Matrix6d> ldlt(0.5 * (P + solve.cov + (P + solve.cov).transpose()));
	if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return solve;
	const Matrix6d K = ldlt.solve(P.transpose()).transpose();  // P (P + R)^-1
	const Vector6d xi = geometry::localLeft(solve.T, prediction.T);
	TPoseWithCov f;
	f.T = geometry::retractLeft(K * xi, prediction.T);
	const Matrix6d C = (Matrix6d::Identity() - K) * P;
	f.cov = 0.5 * (C + C.transpose());
	if (!f.T.matrix().allFinite() || !f.cov.allFinite()) return solve;
	return f;
}

std::string toString(AcceptanceVerdict v)
{
	switch (v)
	{
		case AcceptanceVerdict::Fix: return "fix";
		case AcceptanceVerdict::Unconfirmed: return "unconfirmed";
		case AcceptanceVerdict::Uncounted: return "uncounted";
		case AcceptanceVerdict::PredictionInconsistent: return "prediction_inconsistent";
		case AcceptanceVerdict::MotionInconsistent: return "motion_inconsistent";
	}
	return "?";
}

double FixAcceptance::predictionGate(const TSolve& s) const
{
	// The near misses that pass the 99 % gate are uncertain solves 3-4 sigma
	// from a good prediction (docs/localisation.md, "Uncertain solves"): an
	// uncertain solve must agree more closely before it counts.
	const bool uncertain = m_opts.uncertain_sigma_m > 0 && geometry::translationSigma(s.pose.cov) >= m_opts.uncertain_sigma_m;
	return uncertain ? std::min(m_opts.prediction_chi2, m_opts.uncertain_prediction_chi2) : m_opts.prediction_chi2;
}

TAcceptance FixAcceptance::judge(
	const TSolve& s, const TKeyframePose& pred, const TMotion& motion, bool trackConfirmed, bool countable,
	const KeyframeLink& link)
{
	TAcceptance a;
	bool consistent = true;
	if (pred.valid)
	{
		a.prediction_d2 = predictionDistance2(s.pose, pred, link);
		if (a.prediction_d2 > predictionGate(s))
		{
			consistent = false;
			a.verdict = AcceptanceVerdict::PredictionInconsistent;
		}
	}
	const bool motionTested = m_ref && m_ref->frame + 1 == s.frame && motion.valid;
	if (motionTested)
	{
		// The two solves' frame-to-frame motion: T_prev_curr = T_refkf_prev^-1 T_refkf_kf T_kf_curr.
		const TPoseWithCov D = geometry::compose(
			geometry::compose(geometry::inverse(m_ref->pose.withCov()), link(m_ref->pose.kf, s.pose.kf)), s.pose.withCov());
		a.motion_d2 = mahalanobis2(geometry::localLeft(D.T, motion.T_prev_curr), D.cov + motion.cov);
		if (a.motion_d2 > m_opts.motion_chi2 && consistent)
		{
			consistent = false;
			a.verdict = AcceptanceVerdict::MotionInconsistent;
		}
	}
	if (!consistent)
	{
		noSolve();	// a rejected solve is never a reference
		a.consistent = 0;
		return a;
	}
	if (!countable)
	{
		// Neither a failure nor evidence: the chain waits, with no reference.
		m_ref.reset();
		a.verdict = AcceptanceVerdict::Uncounted;
		a.consistent = m_consistent;
		return a;
	}
	m_ref = s;
	if (motionTested) m_consistent++;
	if (m_consistent >= m_opts.consistent_frames) m_confirmed = true;
	a.consistent = m_consistent;
	a.verdict = (m_confirmed || trackConfirmed) ? AcceptanceVerdict::Fix : AcceptanceVerdict::Unconfirmed;
	return a;
}

void FixAcceptance::noSolve()
{
	m_ref.reset();
	m_consistent = 0;
	m_confirmed = false;
}

void FixAcceptance::startFrom(size_t frame, const TKeyframePose& place)
{
	noSolve();
	m_ref = TSolve{frame, place};
	m_consistent = 1;
	m_confirmed = m_consistent >= m_opts.consistent_frames;
}

void FixAcceptance::reset() { noSolve(); }

}  // namespace shadyloc::localisation
