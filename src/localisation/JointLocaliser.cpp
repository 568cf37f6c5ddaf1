/* ShadyLoc — one solve over several channels' correspondences (JointLocaliser.h). */
#include <shadyloc/localisation/JointLocaliser.h>
#include <shadyloc/localisation/FixEstimate.h>
#include <shadyloc/core/Units.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace shadyloc::localisation
{
JointLocaliser::JointLocaliser(
	const CKeyframeMap& map, const std::vector<std::string>& channels, const TLocaliserOptions& o, int threads)
	: m_map(map),
	  m_channels(channels),
	  m_opts(o),
	  m_threads(threads),
	  m_estimator(estimatorOptionsFor(o)),
	  m_accept(acceptanceOptionsFor(o))
{
	m_opts.validate();
	if (m_channels.size() < 2) throw std::invalid_argument("joint: names fewer than two channels");
	for (const auto& c : m_channels) map.channelIndex(c);  // throws naming the map's channels
}

void keepJointShare(TSearchedCorrespondences& s, bool channelFix, JointPatchMatches take)
{
	const bool patches = take == JointPatchMatches::All || (take == JointPatchMatches::OfFixes && channelFix);
	if (!patches) s.corr.resize(std::min(s.corr.size(), s.patch_from));
}

geometry::TPoseWithCov JointLocaliser::between(uint32_t a, uint32_t b) const
{
	return keyframeLink(m_map, m_opts, a, b);
}

std::vector<geometry::TStereoCorrespondence> JointLocaliser::unionIn(
	uint32_t ref, const std::vector<const TSearchedCorrespondences*>& parts) const
{
	std::vector<geometry::TStereoCorrespondence> all;
	const geometry::TStereoCalib calibKf = m_map.calibration();
	for (const auto* p : parts)
	{
		if (!p) continue;
		// Channels that chose another keyframe (a tighter seed of their own)
		// are moved into ref's frame through the map's chain.
		const Eigen::Isometry3d T_ref_k = between(ref, p->kf).T;
		for (auto c : p->corr)
			if (p->kf == ref || intoReference(c, T_ref_k, calibKf)) all.push_back(c);
	}
	return all;
}

TLocaliserResult JointLocaliser::notRun(const TLocaliserInput& in) const
{
	TLocaliserResult r;
	r.frame = in.frame;
	r.timestamp = in.timestamp;
	r.channel = kLabel;
	r.status = LocaliserStatus::NotRun;
	return r;
}

TLocaliserResult JointLocaliser::localise(
	const TLocaliserInput& in, const std::vector<const TSearchedCorrespondences*>& parts)
{
	const auto t0 = std::chrono::steady_clock::now();
	TLocaliserResult r;
	r.frame = in.frame;
	r.timestamp = in.timestamp;
	r.channel = kLabel;
	auto fail = [&](LocaliserStatus s) {
		r.status = s;
		m_accept.noSolve();
		r.consistent = 0;
		r.ms = core::msSince(t0);
		return r;
	};
	if (!in.prediction.valid) return fail(LocaliserStatus::NoPrediction);
	const TSearchedCorrespondences* first = nullptr;
	for (const auto* p : parts)
		if (p && !p->corr.empty() && !first) first = p;
	if (!first) return fail(LocaliserStatus::NoKeyframe);
	const auto& kf = m_map.keyframe(first->kf);
	r.kf_id = kf.id;
	r.kf_run = kf.run;
	r.kf_frame = kf.frame;
	r.kf_stamp = kf.timestamp;

	const std::vector<geometry::TStereoCorrespondence> corr = unionIn(first->kf, parts);
	r.matches = static_cast<int>(corr.size());
	if (r.matches < m_opts.min_matches) return fail(LocaliserStatus::FewMatches);
	vo::TRelativePoseInput pi;
	pi.calib = in.calib;
	pi.T_curr_ref_pred = nullptr;
	pi.seed = static_cast<uint32_t>(in.frame * 2654435761u + 11);
	pi.corr = &corr;
	vo::TRelativePoseOutput po;
	m_estimator.estimate(pi, po);
	r.inliers = static_cast<int>(po.inliers);
	r.rms_px = po.rms_px;
	if (po.status == vo::RelativePoseStatus::SolverFailed) return fail(LocaliserStatus::SolverFailed);
	if (!po.ok() || r.inliers < m_opts.min_inliers) return fail(LocaliserStatus::FewInliers);

	describeSolve(m_opts, in.calib, corr, po, in.frame, r, m_threads);
	acceptSolve(m_accept, m_opts, in, [this](uint32_t a, uint32_t b) { return between(a, b); }, r);
	r.ms = core::msSince(t0);
	return r;
}

}  // namespace shadyloc::localisation
