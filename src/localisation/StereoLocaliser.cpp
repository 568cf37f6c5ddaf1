/* ShadyLoc — one localiser (active search, solve, failure test, global search). */
#include <shadyloc/localisation/StereoLocaliser.h>
#include <shadyloc/localisation/FixEstimate.h>
#include <shadyloc/core/Units.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace shadyloc::localisation
{
using geometry::TPoseWithCov;

namespace
{
using core::kDeg;
using core::msSince;
using core::timed;

double angleBetweenAxesDeg(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B)
{
	const double c = std::clamp(A.linear().col(2).dot(B.linear().col(2)), -1.0, 1.0);
	return std::acos(c) / kDeg;
}


vo::TKeyframeMatcherOptions placeMatcherOptions(const TLocaliserOptions& o)
{
	vo::TKeyframeMatcherOptions m = matcherOptionsFor(o, SearchMode::Window);
	m.search_radius_px = m.search_radius_lost_px = o.global_window_px;
	return m;
}

}  // namespace

vo::TKeyframeMatcherOptions matcherOptionsFor(const TLocaliserOptions& o, SearchMode mode)
{
	vo::TKeyframeMatcherOptions m;
	m.max_hamming = o.max_hamming;
	m.match_ratio = o.match_ratio;
	m.refine_min_zncc = o.refine_min_zncc;
	m.refine_radius = o.refine_radius_px;
	m.refine_iterations = o.refine_iterations;
	m.patch_search_radius_px = o.patch_search_radius_px;
	m.patch_min_zncc = o.patch_min_zncc;
	m.sigma_px = o.sigma_px;
	m.min_matches = 0;	// never widen on its own: the localiser decides
	switch (mode)
	{
		case SearchMode::Gate:
			m.region = vo::SearchRegion::Gate;
			m.gate_chi2 = o.gate_chi2;
			m.gate_min_px = o.gate_min_px;
			m.gate_max_px = o.gate_max_px;
			m.gate_landmark_max_px = o.gate_landmark_max_px;
			m.gate_clamp = false;
			m.warp = o.warp_patches;
			m.warp_min_distortion = o.warp_min_distortion;
			break;
		case SearchMode::Window:
			m.region = vo::SearchRegion::Circle;
			m.search_radius_px = m.search_radius_lost_px = o.window_px;
			m.warp = o.warp_patches;
			m.warp_min_distortion = o.warp_min_distortion;
			break;
		case SearchMode::Global:
			// A circle larger than any image around an identity projection:
			// every measurement of the frame is a candidate.
			m.region = vo::SearchRegion::Circle;
			m.search_radius_px = m.search_radius_lost_px = 1e5;
			break;
	}
	return m;
}

vo::TRelativePoseOptions estimatorOptionsFor(const TLocaliserOptions& o)
{
	vo::TRelativePoseOptions p;
	p.ransac_threshold_px = o.ransac_threshold_px;
	p.ransac_iterations = o.ransac_iterations;
	p.sigma_px = o.sigma_px;
	p.sigma_disparity_px = o.sigma_disparity_px;
	p.huber_k = o.huber_k;
	p.two_view_ba = o.two_view_ba;
	// Solved without the motion prior: see the file comment of StereoLocaliser.h.
	p.ransac_prediction = false;
	p.ransac_prior_sigma_m = 0;
	p.min_inliers = 6;	// the localiser's own bounds (min_inliers, global_min_inliers) apply after
	return p;
}

TAcceptanceOptions acceptanceOptionsFor(const TLocaliserOptions& o)
{
	TAcceptanceOptions a;
	a.prediction_chi2 = o.prediction_chi2;
	a.uncertain_sigma_m = o.uncertain_sigma_m;
	a.uncertain_prediction_chi2 = o.uncertain_prediction_chi2;
	a.motion_chi2 = o.motion_chi2;
	a.consistent_frames = o.consistent_frames;
	return a;
}

std::string toString(SearchMode m)
{
	switch (m)
	{
		case SearchMode::Gate: return "gate";
		case SearchMode::Window: return "window";
		case SearchMode::Global: return "global";
	}
	return "?";
}

std::string toString(LocaliserStatus s)
{
	switch (s)
	{
		case LocaliserStatus::Ok: return "ok";
		case LocaliserStatus::Unconfirmed: return "unconfirmed";
		case LocaliserStatus::NoPrediction: return "no_prediction";
		case LocaliserStatus::NoKeyframe: return "no_keyframe";
		case LocaliserStatus::Lost: return "lost";
		case LocaliserStatus::FewMatches: return "few_matches";
		case LocaliserStatus::FewInliers: return "few_inliers";
		case LocaliserStatus::SolverFailed: return "solver_failed";
		case LocaliserStatus::Uncertain: return "uncertain";
		case LocaliserStatus::PredictionInconsistent: return "prediction_inconsistent";
		case LocaliserStatus::MotionInconsistent: return "motion_inconsistent";
		case LocaliserStatus::Contradicted: return "contradicted";
		case LocaliserStatus::NotRun: return "not_run";
	}
	return "?";
}

StereoLocaliser::StereoLocaliser(const CKeyframeMap& map, const std::string& channel, const TLocaliserOptions& o)
	: m_map(map),
	  m_channel(channel),
	  m_opts(o),
	  m_matcher(matcherOptionsFor(o, o.search)),
	  m_gateMatcher(matcherOptionsFor(o, SearchMode::Gate)),
	  m_placeMatcher(placeMatcherOptions(o)),
	  m_estimator(estimatorOptionsFor(o)),
	  m_brief(
		  map.channels()[map.channelIndex(channel)].brief_patch_size,
		  map.channels()[map.channelIndex(channel)].brief_seed),
	  m_accept(acceptanceOptionsFor(o))
{
	m_opts.validate();
	map.channelIndex(channel);	// throws naming the map's channels
	for (uint32_t k = 0; k < map.keyframeCount(); k++)
		m_placeIndex.addGroup(map.measurements(k, channel), [](const features::TStereoMeasurement& m) { return m.desc; });
}

void StereoLocaliser::reset() { m_accept.reset(); }

const features::BriefExtractor* StereoLocaliser::briefPattern() const
{
	return m_map.channels()[m_map.channelIndex(m_channel)].descriptor == features::DescriptorKind::Brief ? &m_brief
																										   : nullptr;
}

TPoseWithCov StereoLocaliser::between(uint32_t a, uint32_t b) const { return keyframeLink(m_map, m_opts, a, b); }

namespace
{
/** T_kf_live of `pred` re-expressed in keyframe c through `link`. */
TKeyframePose inKeyframe(uint32_t c, const TKeyframePose& pred, const TPoseWithCov& T_c_predkf)
{
	TPoseWithCov p;
	p.T = pred.T_kf_live;
	p.cov = pred.cov;
	const TPoseWithCov q = geometry::compose(T_c_predkf, p);
	TKeyframePose out;
	out.valid = true;
	out.kf = c;
	out.T_kf_live = q.T;
	out.cov = q.cov;
	return out;
}
}  // namespace

TKeyframePose StereoLocaliser::chooseKeyframe(const TKeyframePose& pred) const
{
	const auto ks = chooseKeyframes(pred);
	return ks.empty() ? TKeyframePose() : ks.front();
}

std::vector<TKeyframePose> StereoLocaliser::chooseKeyframes(const TKeyframePose& pred) const
{
	const auto& o = m_opts;
	const Eigen::Isometry3d T_map_pred = m_map.keyframe(pred.kf).T_map_kf * pred.T_kf_live;
	// The point the keyframe should be nearest: look-ahead metres in front of the camera.
	const Eigen::Vector3d ahead = T_map_pred * Eigen::Vector3d(0, 0, o.kf_lookahead_m);
	std::vector<uint32_t> cands = m_map.keyframesAlongChain(pred.kf, o.kf_back_m, o.kf_ahead_m);
	// At a segment's end (or a VO break) the chain does not go on: also the
	// spatially nearest keyframes of any segment (and experience) of its frame.
	map::TNearestQuery q;
	q.max_distance_m = o.kf_max_distance_m;
	q.max_angle_deg = o.kf_max_angle_deg;
	q.max_results = 5 * static_cast<size_t>(o.kf_experiences_per_frame);
	q.same_frame_as = pred.kf;
	for (const auto& h : m_map.nearestKeyframes(T_map_pred, q))
		if (std::find(cands.begin(), cands.end(), h.id) == cands.end()) cands.push_back(h.id);
	// Each candidate in range with its score: distance from the look-ahead
	// point plus heading; ties (identical scores) go to the smaller id.
	std::vector<std::pair<double, uint32_t>> scored;
	for (const uint32_t c : cands)
	{
		const auto& T_map_c = m_map.keyframe(c).T_map_kf;
		const double ang = angleBetweenAxesDeg(T_map_c, T_map_pred);
		const double dist = (T_map_c.translation() - T_map_pred.translation()).norm();
		if (ang > o.kf_max_angle_deg || dist > o.kf_max_distance_m) continue;
		scored.push_back({(T_map_c.translation() - ahead).norm() + o.kf_angle_weight_m_per_deg * ang, c});
	}
	std::sort(scored.begin(), scored.end());
	// The best of each experience, the prediction's first (kf_stay_in_experience).
	const uint16_t own = m_map.keyframe(pred.kf).run;
	std::vector<uint32_t> chosen;
	std::vector<uint16_t> runs;
	if (o.kf_stay_in_experience)
		for (const auto& [score, c] : scored)
			if (m_map.keyframe(c).run == own)
			{
				chosen.push_back(c);
				runs.push_back(own);
				break;
			}
	for (const auto& [score, c] : scored)
	{
		if (static_cast<int>(chosen.size()) >= o.kf_experiences_per_frame) break;
		const uint16_t run = m_map.keyframe(c).run;
		if (std::find(runs.begin(), runs.end(), run) != runs.end()) continue;
		chosen.push_back(c);
		runs.push_back(run);
	}
	std::vector<TKeyframePose> out;
	for (const uint32_t c : chosen) out.push_back(inKeyframe(c, pred, between(c, pred.kf)));
	return out;
}

std::vector<uint32_t> StereoLocaliser::window(uint32_t ref, const Eigen::Isometry3d& T_map_pred) const
{
	std::vector<uint32_t> w = {ref};
	if (m_opts.kf_window_m <= 0 || m_opts.kf_window_max <= 1) return w;
	std::vector<std::pair<double, uint32_t>> near;	// (distance from the prediction, id)
	for (const uint32_t k : m_map.keyframesAlongChain(ref, m_opts.kf_window_m, m_opts.kf_window_m))
	{
		const auto& T = m_map.keyframe(k).T_map_kf;
		if (k == ref || angleBetweenAxesDeg(T, T_map_pred) > m_opts.kf_max_angle_deg) continue;
		near.emplace_back((T.translation() - T_map_pred.translation()).norm(), k);
	}
	std::sort(near.begin(), near.end());
	for (const auto& dk : near)
		if (static_cast<int>(w.size()) < m_opts.kf_window_max) w.push_back(dk.second);
	return w;
}

void StereoLocaliser::searchLocalMapByPatches(
	const TLocaliserInput& in, uint32_t ref, const Eigen::Isometry3d& T_curr_ref, vo::TKeyframeMatchOutput& out,
	std::vector<uint32_t>& keyframeOf) const
{
	const geometry::TStereoCalib calibKf = m_map.calibration();
	cv::Mat occupied = cv::Mat::zeros(in.meas->left.size(), CV_8UC1);
	for (const auto& c : out.corr)
	{
		const int x = static_cast<int>(std::lround(c.z_curr.x())), y = static_cast<int>(std::lround(c.z_curr.y()));
		if (x >= 0 && y >= 0 && x < occupied.cols && y < occupied.rows) occupied.at<uint8_t>(y, x) = 1;
	}
	const Eigen::Isometry3d T_map_curr = m_map.keyframe(ref).T_map_kf * T_curr_ref.inverse();
	for (const uint32_t k : window(ref, T_map_curr))
	{
		const auto& lms = m_map.measurements(k, m_channel);
		std::vector<uint8_t> skip(lms.size(), 0);
		for (size_t c = 0; c < out.landmark.size(); c++)
			if (keyframeOf[c] == k) skip[static_cast<size_t>(out.landmark[c])] = 1;
		const Eigen::Isometry3d T_ref_k = between(ref, k).T;
		vo::TKeyframeMatchInput mi;
		mi.landmarks = &lms;
		mi.calib_kf = calibKf;
		mi.frame = in.meas;
		mi.calib = in.calib;
		mi.T_curr_kf_pred = T_curr_ref * T_ref_k;
		mi.brief = briefPattern();
		vo::TKeyframeMatchOutput mo;
		m_gateMatcher.searchPatches(mi, skip, occupied, mo);
		for (size_t c = 0; c < mo.corr.size(); c++)
		{
			geometry::TStereoCorrespondence corr = mo.corr[c];
			if (k != ref && !intoReference(corr, T_ref_k, calibKf)) continue;
			out.corr.push_back(corr);
			out.landmark.push_back(mo.landmark[c]);
			out.measurement.push_back(-1);
			keyframeOf.push_back(k);
		}
		out.warped += mo.warped;
	}
}

void StereoLocaliser::searchLocalMap(
	const TLocaliserInput& in, uint32_t ref, const TKeyframePose& pred, double gateScale,
	vo::TKeyframeMatchOutput& out, std::vector<uint32_t>& keyframeOf) const
{
	out = vo::TKeyframeMatchOutput();
	keyframeOf.clear();
	const geometry::TStereoCalib calibKf = m_map.calibration();
	const Eigen::Isometry3d T_map_pred = m_map.keyframe(ref).T_map_kf * pred.T_kf_live;
	const TPoseWithCov p = pred.withCov();
	// A live measurement goes to the landmark of the keyframe nearest the
	// live camera (searched first): the most similar viewpoint.
	std::vector<uint8_t> taken(in.meas->meas.size(), 0);
	for (const uint32_t k : window(ref, T_map_pred))
	{
		const TPoseWithCov T_ref_k = between(ref, k);
		const TPoseWithCov inK = k == ref ? p : geometry::compose(geometry::inverse(T_ref_k), p);
		const TPoseWithCov pinv = geometry::inverse(inK);
		vo::TKeyframeMatchInput mi;
		mi.landmarks = &m_map.measurements(k, m_channel);
		mi.calib_kf = calibKf;
		mi.frame = in.meas;
		mi.calib = in.calib;
		mi.T_curr_kf_pred = pinv.T;
		mi.cov_T_curr_kf_pred = pinv.cov * (gateScale * gateScale);
		mi.brief = briefPattern();
		mi.taken = &taken;	// not refined again for a farther keyframe
		vo::TKeyframeMatchOutput mo;
		m_matcher.match(mi, mo);
		if (k == ref) out.gate = mo.gate;  // the lost test reads the reference keyframe's gates
		out.descriptor_matches += mo.descriptor_matches;
		out.warped += mo.warped;
		for (size_t c = 0; c < mo.corr.size(); c++)
		{
			const int m = mo.measurement[c];  // never a taken one (mi.taken)
			geometry::TStereoCorrespondence corr = mo.corr[c];
			if (k != ref && !intoReference(corr, T_ref_k.T, calibKf)) continue;
			taken[static_cast<size_t>(m)] = 1;
			out.corr.push_back(corr);
			out.landmark.push_back(mo.landmark[c]);
			out.measurement.push_back(m);
			keyframeOf.push_back(k);
		}
	}
}

namespace
{
/** The correspondences' live pixels, marked where the solve kept them (a
 * solve of another search than mo's, after a retry, marks none). */
std::vector<TLiveMatch> liveMatchesOf(const vo::TKeyframeMatchOutput& mo, const vo::TRelativePoseOutput& po)
{
	const bool marked = po.inlier.size() == mo.corr.size();
	std::vector<TLiveMatch> out(mo.corr.size());
	for (size_t i = 0; i < out.size(); i++)
		out[i] = {float(mo.corr[i].z_curr.x()), float(mo.corr[i].z_curr.y()), marked && po.inlier[i] != 0};
	return out;
}
}  // namespace

TLocaliserResult StereoLocaliser::localise(const TLocaliserInput& in, TSearchedCorrespondences* searched)
{
	const auto t0 = std::chrono::steady_clock::now();
	const auto& o = m_opts;
	if (!in.meas) throw std::invalid_argument("StereoLocaliser::localise: no measurements");
	TLocaliserResult r;
	r.frame = in.frame;
	r.timestamp = in.timestamp;
	r.channel = m_channel;
	if (searched) *searched = TSearchedCorrespondences();
	// Any frame without a consistent solve is a failure: consistency starts again.
	auto fail = [&](LocaliserStatus s) {
		r.status = s;
		m_accept.noSolve();
		r.consistent = 0;
		r.ms = msSince(t0);
		return r;
	};
	if (!in.prediction.valid) return fail(LocaliserStatus::NoPrediction);

	// ---- 1. keyframe choice (one per experience searched), around where to search ------
	const auto preds = chooseKeyframes(in.search.valid ? in.search : in.prediction);
	if (preds.empty()) return fail(LocaliserStatus::NoKeyframe);

	// ---- 2. active search in the local map, 3. RANSAC and the robust solve ---------------
	// In each experience chosen; the solve with the most inliers is the frame's.
	TSearchAttempt best;
	for (const TKeyframePose& pred : preds)
	{
		TSearchAttempt a = searchAttempt(in, pred, r);
		const bool better = !best.tried || (a.status == LocaliserStatus::Ok &&
											(best.status != LocaliserStatus::Ok || a.po.inliers > best.po.inliers));
		if (better) best = std::move(a);
	}
	r = std::move(best.r);
	vo::TKeyframeMatchOutput& mo = best.mo;
	const vo::TRelativePoseOutput& po = best.po;
	const LocaliserStatus searchStatus = best.status;
	if (searchStatus == LocaliserStatus::NoKeyframe) return fail(LocaliserStatus::NoKeyframe);
	r.live_matches = liveMatchesOf(mo, po);
	// What the search found, solved or not, handed on once this frame is done
	// with it: the joint localiser's share (correspondences in the matched
	// keyframe, reported as the chosen one).
	auto handOver = [&] {
		if (!searched || searchStatus == LocaliserStatus::Lost) return;
		searched->kf = r.kf_id;
		searched->corr = std::move(mo.corr);
		searched->patch_from = searched->corr.size() - std::min(searched->corr.size(), size_t(std::max(0, r.patch_matches)));
	};
	if (searchStatus != LocaliserStatus::Ok)
	{
		handOver();
		return fail(searchStatus);
	}
	timed(r.ms_stage.covariance, [&] { describeSolve(o, in.calib, mo.corr, po, in.frame, r); });
	handOver();

	// ---- 4. acceptance (FixAcceptance.h) ---------------------------------------------------
	acceptSolve(m_accept, o, in, [this](uint32_t a, uint32_t b) { return between(a, b); }, r);
	r.ms = msSince(t0);
	return r;
}

StereoLocaliser::TSearchAttempt StereoLocaliser::searchAttempt(
	const TLocaliserInput& in, const TKeyframePose& pred, const TLocaliserResult& r0) const
{
	TSearchAttempt a;
	a.tried = true;
	a.r = r0;
	const auto& kf = m_map.keyframe(pred.kf);
	a.r.kf_id = kf.id;
	a.r.kf_run = kf.run;
	a.r.kf_frame = kf.frame;
	a.r.kf_stamp = kf.timestamp;
	uint32_t matchKf = pred.kf;
	if (m_opts.fault_keyframe_offset != 0)
	{
		const long long f = static_cast<long long>(pred.kf) + m_opts.fault_keyframe_offset;
		matchKf = static_cast<uint32_t>(std::clamp<long long>(f, 0, static_cast<long long>(m_map.keyframeCount()) - 1));
		// Clamped at the chain's end onto the chosen keyframe itself: no fault
		// to inject, and a sound solve here would count as a rejected fault.
		if (matchKf == pred.kf)
		{
			a.status = LocaliserStatus::NoKeyframe;
			return a;
		}
	}
	a.status = searchAndSolve(in, matchKf, pred, a.mo, a.po, a.r);
	return a;
}

LocaliserStatus StereoLocaliser::searchAndSolve(
	const TLocaliserInput& in, uint32_t ref, const TKeyframePose& pred, vo::TKeyframeMatchOutput& mo,
	vo::TRelativePoseOutput& po, TLocaliserResult& r) const
{
	const auto& o = m_opts;
	vo::TRelativePoseInput pi;
	pi.calib = in.calib;
	pi.T_curr_ref_pred = nullptr;
	pi.seed = static_cast<uint32_t>(in.frame * 2654435761u + 7);
	LocaliserStatus status = LocaliserStatus::Ok;
	std::vector<uint32_t> keyframeOf;  // per correspondence of mo: its landmark's keyframe
	// A frame that fails both searches reports its first (the gates as predicted).
	TLocaliserResult first;
	bool retried = false;
	for (int attempt = 0; attempt < 2; attempt++)
	{
		if (attempt == 1)
		{
			// Wider gates: a prediction whose covariance is too small for its error.
			if (o.retry_gate_scale <= 1.0 || o.search != SearchMode::Gate) break;
			first = r;
			retried = true;
		}
		timed(r.ms_stage.search, [&] {
			searchLocalMap(in, ref, pred, attempt == 0 ? 1.0 : o.retry_gate_scale, mo, keyframeOf);
		});
		r.gate = mo.gate;
		r.matches = static_cast<int>(mo.corr.size());
		r.warped = mo.warped;
		if (o.search == SearchMode::Gate && mo.gate.predicted > 0 &&
			mo.gate.overflow > o.max_overflow_fraction * mo.gate.predicted)
		{
			status = attempt == 0 ? LocaliserStatus::Lost : status;
			break;
		}
		if (r.matches < o.min_matches)
		{
			status = LocaliserStatus::FewMatches;
			continue;
		}
		pi.corr = &mo.corr;
		po = vo::TRelativePoseOutput();
		timed(r.ms_stage.solve, [&] { m_estimator.estimate(pi, po); });
		r.inliers = static_cast<int>(po.inliers);
		r.rms_px = po.rms_px;
		if (po.status == vo::RelativePoseStatus::SolverFailed)
		{
			status = LocaliserStatus::SolverFailed;
			break;
		}
		status = (!po.ok() || r.inliers < o.min_inliers) ? LocaliserStatus::FewInliers : LocaliserStatus::Ok;
		if (status == LocaliserStatus::Ok) break;
	}
	if (status != LocaliserStatus::Ok && retried)
	{
		r.gate = first.gate;
		r.matches = first.matches;
		r.warped = first.warped;
		r.inliers = first.inliers;
		r.rms_px = first.rms_px;
	}
	// The second pass: at the solved pose (or, when the descriptors found
	// too little, at the prediction of a confirmed track) the unmatched
	// landmarks are found by their patches alone, and the frame is solved again.
	const bool solved = status == LocaliserStatus::Ok;
	// A track known to centimetres predicts a near landmark to a pixel or
	// two: a confirmed one, or a verified place just found.
	const bool sharp = in.track_confirmed || translationSigma(in.prediction.cov) <= o.patch_prediction_max_sigma_m;
	const bool fromPrediction = !solved && o.patch_search_from_prediction && sharp &&
								(status == LocaliserStatus::FewMatches || status == LocaliserStatus::FewInliers);
	const bool heldByDescriptors = solved && o.patch_search_max_inliers > 0 && r.inliers >= o.patch_search_max_inliers;
	if (o.patch_search && !heldByDescriptors && (solved || fromPrediction))
	{
		// The prediction is taken in `ref`, as the first pass took it.
		const Eigen::Isometry3d T_curr_ref = solved ? po.T_curr_ref : pred.T_kf_live.inverse();
		vo::TKeyframeMatchOutput more = mo;
		timed(r.ms_stage.patch_search, [&] { searchLocalMapByPatches(in, ref, T_curr_ref, more, keyframeOf); });
		const int added = static_cast<int>(more.corr.size() - mo.corr.size());
		vo::TRelativePoseOutput po2;
		if (added > 0 && static_cast<int>(more.corr.size()) >= o.min_matches)
		{
			pi.corr = &more.corr;
			timed(r.ms_stage.patch_solve, [&] { m_estimator.estimate(pi, po2); });
		}
		// At the prediction the patches are found where the prediction puts
		// them, so they agree with it whether it is right or not: the solve
		// must also hold descriptor matches, found without it (a wrong
		// keyframe under the fault injection otherwise passed as a fix).
		int descriptorInliers = 0;
		for (size_t c = 0; c < mo.corr.size() && c < po2.inlier.size(); c++) descriptorInliers += po2.inlier[c] != 0;
		const bool better = solved ? po2.ok() && po2.inliers >= po.inliers
								   : po2.ok() && static_cast<int>(po2.inliers) >= o.min_inliers &&
										 descriptorInliers >= o.patch_prediction_min_descriptor_inliers;
		if (better)
		{
			mo = std::move(more);
			po = po2;
			r.matches = static_cast<int>(mo.corr.size());
			r.warped = mo.warped;
			r.patch_matches = added;
			r.inliers = static_cast<int>(po.inliers);
			r.rms_px = po.rms_px;
			status = LocaliserStatus::Ok;
		}
	}
	return status;
}

void StereoLocaliser::putNearestFirst(
	const Eigen::Isometry3d& guess, std::vector<std::pair<int, uint32_t>>& candidates) const
{
	// The keyframe nearest the guessed camera, facing its way: near the
	// guess its landmarks are where the guess puts them even when too few of
	// its descriptors vote (seen from the side of the survey).
	const auto score = [&](uint32_t k) {
		const Eigen::Isometry3d T = m_map.keyframe(k).T_map_kf.inverse() * guess;
		const double facing = Eigen::AngleAxisd(T.linear()).angle();
		return facing > M_PI / 2 ? std::numeric_limits<double>::infinity() : T.translation().norm();
	};
	if (candidates.empty()) return;
	auto nearest = candidates.begin();
	for (auto it = candidates.begin(); it != candidates.end(); ++it)
		if (score(it->second) < score(nearest->second)) nearest = it;
	std::rotate(candidates.begin(), nearest, nearest + 1);
}

TGlobalPlace StereoLocaliser::globalSearch(
	const features::TStereoFrame& meas, const geometry::TStereoCalib& calib, uint32_t seed) const
{
	std::vector<uint32_t> all(m_map.keyframeCount());
	for (uint32_t k = 0; k < all.size(); k++) all[k] = k;
	return globalSearch(meas, calib, seed, all);
}

std::vector<std::pair<int, uint32_t>> StereoLocaliser::placeVotes(
	const features::TStereoFrame& meas, const std::vector<uint32_t>& among) const
{
	// One vote per live feature, to the nearest only: counting instead every
	// landmark with some live descriptor nearby let about half of any
	// keyframe's landmarks vote in any frame (BRIEF of natural images is far
	// from uniform), so the keyframes with the most landmarks won everywhere
	// (on the simulator the street of buildings was never a candidate).
	std::vector<features::TBriefDescriptor> live;
	live.reserve(meas.meas.size());
	for (const auto& m : meas.meas) live.push_back(m.desc);
	std::vector<int> count(among.size(), 0);
	for (const int a : m_placeIndex.nearestGroup(live, among, m_opts.global_vote_hamming))
		if (a >= 0) count[static_cast<size_t>(a)]++;
	std::vector<std::pair<int, uint32_t>> votes;
	votes.reserve(among.size());
	for (size_t a = 0; a < among.size(); a++) votes.emplace_back(-count[a], among[a]);
	std::sort(votes.begin(), votes.end());
	return votes;
}

std::optional<StereoLocaliser::TVerifiedPlace> StereoLocaliser::verifyPlace(
	const features::TStereoFrame& meas, const geometry::TStereoCalib& calib, uint32_t seed, uint32_t k,
	const std::optional<Eigen::Isometry3d>& guess, int& solves) const
{
	const auto& o = m_opts;
	// (1) a window around each landmark's projection: where the guess puts it
	// (warped), else from the keyframe's own pose;
	vo::TKeyframeMatchInput mi;
	mi.landmarks = &m_map.measurements(k, m_channel);
	mi.calib_kf = m_map.calibration();
	mi.frame = &meas;
	mi.calib = calib;
	vo::TKeyframeMatchOutput mo;
	vo::TRelativePoseOutput po;
	vo::TRelativePoseInput pi;
	pi.calib = calib;
	pi.seed = seed + k;
	bool verified = false;
	for (const bool atGuess : {true, false})
	{
		if (atGuess && !guess) continue;
		mi.T_curr_kf_pred = atGuess ? guess->inverse() * m_map.keyframe(k).T_map_kf : Eigen::Isometry3d::Identity();
		mi.brief = atGuess ? briefPattern() : nullptr;
		m_placeMatcher.match(mi, mo);
		if (static_cast<int>(mo.corr.size()) < o.min_matches) continue;
		pi.corr = &mo.corr;
		m_estimator.estimate(pi, po);
		solves++;
		// A first pass below min_inliers is what random matches give (RANSAC
		// finds 6-8 consistent ones among ~150 in a world that is not the
		// map's); the gates around such a pose are wide enough for a second
		// pass to gather a spurious consensus, so it is not refined.
		verified = po.ok() && static_cast<int>(po.inliers) >= o.min_inliers;
		if (verified) break;
	}
	if (!verified) return std::nullopt;
	// (2) active search around that pose, solved again (without it as prior).
	mi.T_curr_kf_pred = po.T_curr_ref;
	mi.cov_T_curr_kf_pred = geometry::invertCovariance(po.T_curr_ref.inverse(), o.cov_scale * po.cov_T_ref_curr);
	mi.brief = briefPattern();	// a pose now: the second pass may warp
	vo::TKeyframeMatchOutput mo2;
	m_gateMatcher.match(mi, mo2);
	vo::TRelativePoseOutput po2;
	if (static_cast<int>(mo2.corr.size()) >= o.min_matches)
	{
		pi.corr = &mo2.corr;
		m_estimator.estimate(pi, po2);
	}
	const bool second = po2.ok() && po2.inliers >= po.inliers;
	TVerifiedPlace v;
	v.solve = second ? po2 : po;
	v.corr = second ? mo2.corr : mo.corr;
	if (o.patch_search)
	{
		// The patch pass at the verified pose, as a tracked frame gets it.
		TLocaliserInput li;
		li.meas = &meas;
		li.calib = calib;
		vo::TKeyframeMatchOutput more = second ? mo2 : mo;
		std::vector<uint32_t> keyframeOf(more.corr.size(), k);
		const size_t before = more.corr.size();
		searchLocalMapByPatches(li, k, v.solve.T_curr_ref, more, keyframeOf);
		vo::TRelativePoseOutput po3;
		if (more.corr.size() > before)
		{
			pi.corr = &more.corr;
			m_estimator.estimate(pi, po3);
		}
		if (po3.ok() && po3.inliers >= v.solve.inliers)
		{
			v.solve = po3;
			v.corr = std::move(more.corr);
		}
	}
	v.kf = k;
	v.inliers = static_cast<int>(v.solve.inliers);
	v.T_kf_live = v.solve.T_curr_ref.inverse();
	v.T_map_live = m_map.keyframe(k).T_map_kf * v.T_kf_live;
	return v;
}

TGlobalPlace StereoLocaliser::bestPlace(
	const std::vector<TVerifiedPlace>& ver, const geometry::TStereoCalib& calib, uint32_t seed) const
{
	const auto& o = m_opts;
	TGlobalPlace out;
	const auto bestIt = std::max_element(ver.begin(), ver.end(), [](const TVerifiedPlace& a, const TVerifiedPlace& b) {
		return a.inliers < b.inliers || (a.inliers == b.inliers && a.kf > b.kf);
	});
	const TVerifiedPlace& best = *bestIt;
	// Distance means something only within one frame: a place in an
	// experience linked nowhere may be this very place, so it is no rival.
	const uint32_t frame = m_map.frameOf(best.kf);
	for (const auto& v : ver)
		if (m_map.frameOf(v.kf) == frame &&
			(v.T_map_live.translation() - best.T_map_live.translation()).norm() > o.global_distinct_m)
			out.runner_up_inliers = std::max(out.runner_up_inliers, v.inliers);
	out.inliers = best.inliers;
	out.matches = static_cast<int>(best.corr.size());
	out.votes = best.votes;
	out.pose.kf = best.kf;
	out.pose.T_kf_live = best.T_kf_live;
	// The covariance a tracked solve of the same matches gets (bootstrap
	// included): a place is a fix only under the same sigma bounds.
	out.pose.cov = solveCovariance(m_opts, calib, best.corr, best.solve, seed + best.kf);
	out.certain = withinFixBounds(m_opts, out.pose.cov);
	if (best.inliers < o.global_min_inliers)
	{
		out.why = "best place has " + std::to_string(best.inliers) + " inliers (< " +
				  std::to_string(o.global_min_inliers) + ")";
		return out;
	}
	if (out.runner_up_inliers >= o.global_ambiguity_ratio * best.inliers)
	{
		out.why = "ambiguous: another place has " + std::to_string(out.runner_up_inliers) + " inliers against " +
				  std::to_string(best.inliers);
		return out;
	}
	out.ok = true;
	out.pose.valid = true;
	return out;
}

TGlobalPlace StereoLocaliser::globalSearch(
	const features::TStereoFrame& meas, const geometry::TStereoCalib& calib, uint32_t seed,
	const std::vector<uint32_t>& among, const std::optional<Eigen::Isometry3d>& guess) const
{
	const auto& o = m_opts;
	if (among.empty() || meas.meas.empty())
	{
		TGlobalPlace out;
		out.why = "no keyframes or no measurements";
		return out;
	}
	// ---- BRIEF voting, then the geometric check of the best candidates.
	auto votes = placeVotes(meas, among);
	if (guess) putNearestFirst(*guess, votes);
	std::vector<TVerifiedPlace> ver;
	int solves = 0;
	for (int c = 0; c < o.global_candidates && c < static_cast<int>(votes.size()); c++)
	{
		const bool nearGuess = guess && c == 0;	 // putNearestFirst: no votes needed
		if (!nearGuess && -votes[c].first < o.global_min_votes) continue;
		if (auto v = verifyPlace(meas, calib, seed, votes[c].second, guess, solves))
		{
			v->votes = -votes[c].first;
			ver.push_back(std::move(*v));
		}
	}
	TGlobalPlace out = ver.empty() ? TGlobalPlace{} : bestPlace(ver, calib, seed);
	out.verified = solves;
	if (ver.empty()) out.why = "no candidate verified";
	return out;
}

}  // namespace shadyloc::localisation
