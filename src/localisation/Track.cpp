/* ShadyLoc — the system's track and switching policy (see Track.h). */
#include <shadyloc/localisation/Track.h>
#include <shadyloc/core/Units.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace shadyloc::localisation
{
using geometry::Matrix6d;
using geometry::TPoseWithCov;

namespace
{
using core::kDeg;

/** p composed with the step (its covariance plus `drift`). */
TKeyframePose propagate(const TKeyframePose& p, const TMotion& m, const Matrix6d& drift)
{
	if (!p.valid || !m.valid) return p;
	TPoseWithCov step;
	step.T = m.T_prev_curr;
	step.cov = m.cov + drift;
	const TPoseWithCov c = geometry::compose(p.withCov(), step);
	TKeyframePose out = p;
	out.T_kf_live = c.T;
	out.cov = c.cov;
	return out;
}

}  // namespace

Matrix6d driftCovariance(double before, double step, double k_m, double k_deg)
{
	// Var(k d) grows by k^2 ((d + s)^2 - d^2): a random walk per step would
	// give sigma ~ k sqrt(s d) instead, over-confident and frame-rate dependent.
	const double grow = (before + step) * (before + step) - before * before;
	const double kr = k_deg * kDeg;
	Matrix6d c = Matrix6d::Zero();
	c.diagonal() << k_m * k_m * grow, k_m * k_m * grow, k_m * k_m * grow, kr * kr * grow, kr * kr * grow, kr * kr * grow;
	return c;
}

TKeyframePose Track::predict(const TMotion& motion)
{
	const double step = motion.valid ? motion.T_prev_curr.translation().norm() : 0.0;
	const Matrix6d drift = driftCovariance(m_distSinceFix, step, m_opts.drift_m_per_m, m_opts.drift_deg_per_m);
	m_distSinceFix += step;
	m_pred = propagate(m_est, motion, drift);
	if (m_rival.valid)
	{
		m_rival = propagate(m_rival, motion, driftCovariance(m_rivalDist, step, m_opts.drift_m_per_m, m_opts.drift_deg_per_m));
		m_rivalDist += step;
	}
	m_seedPred = TKeyframePose();
	if (m_seed.valid && m_pred.valid)
	{
		// The seed is one frame's solve: only its own step's drift is added.
		const TKeyframePose s = propagate(m_seed, motion, driftCovariance(0, step, m_opts.drift_m_per_m, m_opts.drift_deg_per_m));
		if (s.cov.topLeftCorner<3, 3>().trace() < m_pred.cov.topLeftCorner<3, 3>().trace()) m_seedPred = s;
	}
	return m_pred;
}

bool Track::confirmed() const
{
	return m_confirmed && m_pred.valid && geometry::translationSigma(m_pred.cov) <= m_opts.confirmed_max_sigma_m;
}

void Track::fix(const TKeyframePose& f)
{
	m_est = f;
	m_est.valid = true;
	m_seed = TKeyframePose();
	m_rival = TKeyframePose();
	m_confirmed = true;
	m_places = 0;
	m_framesSinceFix = 0;
	m_distSinceFix = 0;
}

void Track::noFix(const std::vector<TKeyframePose>& seeds)
{
	m_est = m_pred;
	m_seed = TKeyframePose();
	if (m_opts.seed_with_unconfirmed)
		for (const auto& s : seeds)
			if (s.valid && (!m_seed.valid || s.cov.topLeftCorner<3, 3>().trace() < m_seed.cov.topLeftCorner<3, 3>().trace()))
				m_seed = s;
	if (m_confirmed && !confirmed()) m_confirmed = false;  // outgrew the bound: a new hypothesis is needed
	m_framesSinceFix++;
}

std::vector<uint32_t> MapSweep::next()
{
	const uint32_t n = m_budget > 0 ? std::min(m_keyframes, static_cast<uint32_t>(m_budget)) : m_keyframes;
	std::vector<uint32_t> slice(n);
	for (uint32_t i = 0; i < n; i++) slice[i] = (m_next + i) % m_keyframes;
	if (m_keyframes > 0) m_next = (m_next + n) % m_keyframes;
	std::sort(slice.begin(), slice.end());	// a slice that wraps: still ascending (the votes' tie order)
	return slice;
}

SearchScope Track::searchNeeded(bool allLost) const
{
	if (!m_est.valid || m_framesSinceFix > m_opts.global_search_after_frames) return SearchScope::Whole;
	if (allLost || m_framesSinceFix >= m_opts.relocalise_after_frames) return SearchScope::Window;
	return SearchScope::None;
}

Matrix6d Track::withPlaceSigma(const Matrix6d& cov) const
{
	const double sr = m_opts.global_sigma_deg * kDeg;
	Matrix6d c = Matrix6d::Zero();
	c.diagonal() << Eigen::Vector3d::Constant(m_opts.global_sigma_m * m_opts.global_sigma_m), Eigen::Vector3d::Constant(sr * sr);
	return cov + c;	 // one frame's solve, unconfirmed
}

void Track::adoptPlace(const TKeyframePose& place, bool seedsSearch)
{
	m_est = place;
	m_est.valid = true;
	m_est.cov = withPlaceSigma(place.cov);
	// Where to search next (its own covariance), never what is tested against.
	m_seed = seedsSearch ? place : TKeyframePose();
	m_rival = TKeyframePose();
	m_confirmed = false;
	m_framesSinceFix = 0;
	m_distSinceFix = 0;
}

PlaceOutcome Track::placeFound(
	const TKeyframePose& place, const PlaceTest& agreesWith, bool certain, int K, bool seedsSearch)
{
	const bool confirmedTrack = confirmed();
	const bool agrees = agreesWith(m_est);
	if (agrees && certain && (confirmedTrack || m_places + 1 >= K))
	{
		fix(place);
		return PlaceOutcome::Fix;
	}
	int places = agrees && !confirmedTrack ? m_places + 1 : 1;
	if (confirmedTrack && m_opts.confirmed_track_outranks_places &&
		geometry::translationSigma(withPlaceSigma(place.cov)) >= geometry::translationSigma(m_pred.cov))
	{
		if (agrees) return PlaceOutcome::Outranked;  // it supports the track: nothing to change
		if (!(m_rival.valid && agreesWith(m_rival)))
		{
			m_rival = place;
			m_rival.cov = withPlaceSigma(place.cov);
			m_rivalDist = 0;
			return PlaceOutcome::Outranked;
		}
		// Two places that agree with each other against the track.
		places = 2;
		if (certain && places >= K)
		{
			fix(place);
			return PlaceOutcome::Fix;
		}
	}
	adoptPlace(place, seedsSearch);
	m_places = places;
	return PlaceOutcome::Hypothesis;
}

bool placeAgrees(const TKeyframePose& place, const TKeyframePose& pred, const KeyframeLink& link, double chi2)
{
	return place.valid && pred.valid && predictionDistance2(place, pred, link) <= chi2;
}

size_t chooseFix(
	const std::vector<TKeyframePose>& fixes, const std::vector<double>& sigma_m, const KeyframeLink& link, double chi2)
{
	if (fixes.size() != sigma_m.size()) throw std::invalid_argument("chooseFix: one sigma per fix");
	bool disagree = false;
	for (size_t j = 1; j < fixes.size() && !disagree; j++) disagree = predictionDistance2(fixes[j], fixes[0], link) > chi2;
	if (!disagree) return 0;
	return static_cast<size_t>(std::min_element(sigma_m.begin(), sigma_m.end()) - sigma_m.begin());
}

std::vector<bool> contradictedFixes(
	const std::vector<TKeyframePose>& fixes, const std::vector<double>& sigma_m, const KeyframeLink& link, double chi2)
{
	if (fixes.size() != sigma_m.size()) throw std::invalid_argument("contradictedFixes: one sigma per fix");
	std::vector<size_t> byCertainty(fixes.size());
	for (size_t i = 0; i < fixes.size(); i++) byCertainty[i] = i;
	std::stable_sort(byCertainty.begin(), byCertainty.end(), [&](size_t a, size_t b) { return sigma_m[a] < sigma_m[b]; });
	std::vector<bool> contradicted(fixes.size(), false);
	std::vector<size_t> kept;
	for (const size_t i : byCertainty)
	{
		for (const size_t k : kept)
			if (predictionDistance2(fixes[i], fixes[k], link) > chi2) contradicted[i] = true;
		if (!contradicted[i]) kept.push_back(i);
	}
	return contradicted;
}

}  // namespace shadyloc::localisation
