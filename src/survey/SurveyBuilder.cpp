/* ShadyLoc — building a keyframe map from a survey run. */
#include <shadyloc/survey/SurveyBuilder.h>

#include <shadyloc/geometry/PoseCovariance.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace shadyloc::survey
{
map::TChannelParams channelParams(
	const std::string& label, const CObservationFilter& madeBy, const features::TStereoFeatureOptions& fo)
{
	return map::TChannelParams::From(label, madeBy.GetRuntimeClass()->className, madeBy.imageOptionsAsIni(), fo);
}

std::vector<size_t> selectLandmarkIndices(
	const std::vector<features::TStereoMeasurement>& all, int keep, int cols, int rows, int width, int height,
	const std::vector<int>* score, int minScore)
{
	if (score && score->size() != all.size())
		throw std::invalid_argument(
			"selectLandmarks: " + std::to_string(score->size()) + " scores for " + std::to_string(all.size()) +
			" measurements");
	const bool floor = score && minScore > 0;
	if (!floor && (keep <= 0 || all.size() <= static_cast<size_t>(keep)))
	{
		std::vector<size_t> idx(all.size());
		std::iota(idx.begin(), idx.end(), size_t(0));
		return idx;
	}
	const size_t budget = keep > 0 ? static_cast<size_t>(keep) : all.size();
	cols = std::max(1, cols);
	rows = std::max(1, rows);
	std::vector<std::vector<size_t>> buckets(static_cast<size_t>(cols * rows));
	for (size_t i = 0; i < all.size(); i++)
	{
		if (floor && (*score)[i] < minScore) continue;
		const int c = std::clamp(static_cast<int>(all[i].uL * cols / std::max(1, width)), 0, cols - 1);
		const int r = std::clamp(static_cast<int>(all[i].v * rows / std::max(1, height)), 0, rows - 1);
		buckets[r * cols + c].push_back(i);
	}
	for (auto& b : buckets)
		std::stable_sort(b.begin(), b.end(), [&](size_t x, size_t y) {
			if (score && (*score)[x] != (*score)[y]) return (*score)[x] > (*score)[y];
			return all[x].response > all[y].response ||
				   (all[x].response == all[y].response && all[x].zncc > all[y].zncc);
		});
	std::vector<size_t> out;
	out.reserve(std::min(budget, all.size()));
	for (size_t round = 0; out.size() < budget; round++)
	{
		bool any = false;
		for (const auto& b : buckets)
			if (round < b.size() && out.size() < budget)
			{
				out.push_back(b[round]);
				any = true;
			}
		if (!any) break;
	}
	return out;
}

std::vector<features::TStereoMeasurement> selectLandmarks(
	const std::vector<features::TStereoMeasurement>& all, int keep, int cols, int rows, int width, int height,
	const std::vector<int>* score, int minScore)
{
	std::vector<features::TStereoMeasurement> out;
	for (size_t i : selectLandmarkIndices(all, keep, cols, rows, width, height, score, minScore)) out.push_back(all[i]);
	return out;
}

namespace
{
/** The landmark's disparity from its re-observations where they agree and
 * say more than the pair alone (geometry/LandmarkDepth.h). */
bool refineDepth(
	features::TStereoMeasurement& m, const geometry::TStereoCalib& calib, double sigma_px, double reobservation_sigma_px,
	const std::vector<geometry::TDepthObservation>& obs)
{
	geometry::TDepthRefinementOptions ro;
	ro.sigma_px = sigma_px;
	ro.reobservation_sigma_px = reobservation_sigma_px;
	const auto r = geometry::refineDisparity(calib, Eigen::Vector3d(m.uL, m.v, m.uR), obs, ro);
	if (!r.ok || !(r.sigma_disparity < std::sqrt(2.0) * sigma_px)) return false;
	m.uR = static_cast<float>(m.uL + calib.doffs() - r.disparity);
	m.sigma_d = static_cast<float>(r.sigma_disparity);
	return true;
}
}  // namespace

TReobservationMatching TReobservationMatching::From(const vo::TStereoVOOptions& vo, double radius_px)
{
	TReobservationMatching m;
	m.matcher = vo::matcherOptionsFrom(vo);
	m.matcher.region = vo::SearchRegion::Circle;
	// The VO's pose of a survey frame is good to centimetres: a small circle,
	// no wide retry, and every landmark scored (far ones included).
	m.matcher.search_radius_px = radius_px;
	m.matcher.search_radius_lost_px = radius_px;
	m.matcher.min_matches = 0;
	m.matcher.near_min_disparity = 0;
	m.pose = vo::poseEstimatorOptionsFrom(vo);
	return m;
}

std::vector<int> countReobservations(
	const std::vector<features::TStereoMeasurement>& landmarks, const geometry::TStereoCalib& calib,
	const std::vector<TReobservingFrame>& frames, const TReobservationMatching& m)
{
	std::vector<int> n;
	for (const auto& obs : findReobservations(landmarks, calib, frames, m)) n.push_back(static_cast<int>(obs.size()));
	return n;
}

std::vector<std::vector<geometry::TDepthObservation>> findReobservations(
	const std::vector<features::TStereoMeasurement>& landmarks, const geometry::TStereoCalib& calib,
	const std::vector<TReobservingFrame>& frames, const TReobservationMatching& m)
{
	std::vector<std::vector<geometry::TDepthObservation>> n(landmarks.size());
	if (landmarks.empty()) return n;
	const vo::KeyframeMatcher matcher(m.matcher);
	const vo::RelativePoseEstimator estimator(m.pose);
	for (const auto& f : frames)
	{
		if (!f.frame) throw std::invalid_argument("countReobservations: a frame without measurements");
		vo::TKeyframeMatchInput in;
		in.landmarks = &landmarks;
		in.calib_kf = calib;
		in.frame = f.frame;
		in.calib = calib;
		in.T_curr_kf_pred = f.T_frame_kf;
		vo::TKeyframeMatchOutput out;
		matcher.match(in, out);
		if (out.corr.empty()) continue;
		vo::TRelativePoseInput pin;
		pin.corr = &out.corr;
		pin.calib = calib;
		pin.T_curr_ref_pred = &f.T_frame_kf;
		vo::TRelativePoseOutput po;
		estimator.estimate(pin, po);
		if (!po.ok()) continue;
		geometry::TDepthObservation obs;
		obs.T_obs_kf = po.T_curr_ref;
		obs.cov_T_obs_kf = geometry::invertCovariance(po.T_curr_ref.inverse(), po.cov_T_ref_curr);
		for (size_t i = 0; i < out.corr.size(); i++)
			if (po.inlier[i])
			{
				obs.z = out.corr[i].z_curr;
				n[static_cast<size_t>(out.landmark[i])].push_back(obs);
			}
	}
	return n;
}

SurveyBuilder::SurveyBuilder(CKeyframeMap& map, const std::string& runName, const vo::TStereoVOOptions& vo)
	: mrpt::system::COutputLogger("SurveyBuilder"),
	  m_map(map),
	  m_matching(TReobservationMatching::From(vo, map.options.reobservation_radius_px))
{
	map.options.validate();
	if (map.channels().empty()) throw std::logic_error("SurveyBuilder: set the map up (CKeyframeMap::setup) first");
	m_run = map.addRun(runName);
	if (!map.keyframes().empty()) m_segment = map.keyframes().back().segment + 1;
}

bool SurveyBuilder::offer(
	const vo::TFrameResult& res, const std::vector<vo::TKeyframe>& voKfs, size_t voKfsBefore)
{
	m_pending.valid = false;
	// The VO chain's segments and path distance, frame by frame (re-observation windows).
	m_lastTracked = vo::isTracked(res.status);
	m_lastFrame = res.frame;
	if (res.status == vo::FrameStatus::First || res.status == vo::FrameStatus::Reinit)
	{
		if (m_voStarted) m_voSegment++;
		m_voStarted = true;
		m_voDist = 0;
	}
	else if (m_lastTracked)
		m_voDist += (m_T_world_lastTracked.inverse() * res.T_world_curr).translation().norm();
	if (m_lastTracked) m_T_world_lastTracked = res.T_world_curr;
	if (!m_lastTracked) return false;  // a predicted pose is no place for a keyframe
	TPending p;
	p.res = res;
	const bool restart = res.status == vo::FrameStatus::First || res.status == vo::FrameStatus::Reinit;
	const auto chain = vo::chainReference(res, voKfs, voKfsBefore);
	if (!chain) throw std::logic_error("SurveyBuilder::offer: inconsistent VO keyframe counts for a tracked frame");
	p.ref = chain->ref;
	p.T_ref_f = chain->T_ref_f.T;
	p.cov_ref_f = chain->T_ref_f.cov;
	// T_last_f along the VO chain, unless a break lies between.
	const auto along = restart || !m_segmentOpen
						   ? std::nullopt
						   : vo::poseAlongChain(voKfs, m_lastRef, {m_T_ref_last, m_cov_ref_last}, p.ref, {p.T_ref_f, p.cov_ref_f});
	if (!along)
	{
		p.newSegment = true;
		if (res.status == vo::FrameStatus::Reinit && m_haveOrigin) m_breaks++;
	}
	else
	{
		const geometry::TPoseWithCov& T = *along;
		p.T_prev_f = T.T;
		p.cov_prev_f = T.cov;
		const auto& o = m_map.options;
		const double rotDeg = Eigen::AngleAxisd(T.T.linear()).angle() * 180.0 / M_PI;
		if (T.T.translation().norm() < o.kf_spacing_m && rotDeg < o.kf_spacing_deg) return false;
	}
	p.valid = true;
	m_pending = p;
	return true;
}

void SurveyBuilder::addKeyframe(
	const std::vector<std::vector<features::TStereoMeasurement>>& perChannel,
	const std::optional<Eigen::Isometry3d>& T_gt_kf)
{
	if (!m_pending.valid) throw std::logic_error("SurveyBuilder::addKeyframe without an accepted offer()");
	const auto& p = m_pending;
	map::TMapKeyframe kf;
	kf.run = m_run;
	kf.frame = p.res.frame;
	kf.timestamp = p.res.timestamp;
	kf.T_gt_kf = T_gt_kf;
	if (!m_haveOrigin)
	{
		// The map frame is the first keyframe's left camera.
		m_T_world_map = p.res.T_world_curr;
		m_haveOrigin = true;
	}
	kf.T_map_kf = m_T_world_map.inverse() * p.res.T_world_curr;
	if (p.bridged)
	{
		// The chain VO's world after its break is its own dead reckoning:
		// re-anchored so that this keyframe sits where the bridge puts it.
		kf.T_map_kf = m_T_map_last * p.T_prev_f;
		m_T_world_map = p.res.T_world_curr * kf.T_map_kf.inverse();
		kf.T_prev_kf = p.T_prev_f;
		kf.cov_prev_kf = p.cov_prev_f;
	}
	else if (p.newSegment)
	{
		if (m_segmentOpen) m_segment++;
		// After a break (or a second survey run) the segment's map pose is a
		// prediction through the VO's dead reckoning, never a measurement.
		const bool first = m_map.keyframes().empty() && m_added == 0;
		m_predictedSegment = !first;
		kf.T_prev_kf = first ? Eigen::Isometry3d::Identity() : m_T_map_last.inverse() * kf.T_map_kf;
		kf.cov_prev_kf = first ? geometry::Matrix6d(geometry::Matrix6d::Zero()) : geometry::Matrix6d(geometry::Matrix6d::Identity() * 1e2);
	}
	else
	{
		kf.T_prev_kf = p.T_prev_f;
		kf.cov_prev_kf = p.cov_prev_f;
	}
	kf.segment = m_segment;
	kf.predicted = m_predictedSegment;
	if (perChannel.size() != m_map.channels().size())
		throw std::invalid_argument(
			"SurveyBuilder::addKeyframe: " + std::to_string(perChannel.size()) + " channels of measurements, the map has " +
			std::to_string(m_map.channels().size()));
	m_segmentOpen = true;
	m_lastRef = p.ref;
	m_T_ref_last = p.T_ref_f;
	m_cov_ref_last = p.cov_ref_f;
	m_T_map_last = kf.T_map_kf;
	m_added++;
	m_pending.valid = false;
	TWaiting w;
	w.voSegment = m_voSegment;
	w.dist = m_voDist;
	w.T_world = p.res.T_world_curr;
	w.kf = std::move(kf);
	w.kf.channels = perChannel;
	if (!needsFrames())
	{
		append(std::move(w));
		return;
	}
	m_waiting.push_back(std::move(w));
	flush(false);
}

bool SurveyBuilder::bridgeable() const
{
	return m_pending.valid && m_pending.newSegment && m_segmentOpen && !m_pending.bridged;
}

void SurveyBuilder::bridge(const geometry::TPoseWithCov& T_last_f)
{
	if (!bridgeable()) throw std::logic_error("SurveyBuilder::bridge: no accepted frame opening a segment after a break");
	m_pending.bridged = true;
	m_pending.T_prev_f = T_last_f.T;
	m_pending.cov_prev_f = T_last_f.cov;
	m_bridged++;
}

bool SurveyBuilder::scoresLandmarks() const
{
	const auto& o = m_map.options;
	// Keeping everything needs no score; a floor on it does.
	return o.landmark_selection == TKeyframeMapOptions::LandmarkSelection::Reobserved &&
		   (o.landmarks_per_keyframe > 0 || o.min_reobservations > 0);
}

bool SurveyBuilder::needsFrames() const { return scoresLandmarks() || m_map.options.depth_from_reobservations; }

void SurveyBuilder::addFrame(std::vector<features::TStereoFrame> perChannel)
{
	if (!needsFrames() || !m_lastTracked) return;
	if (perChannel.size() != m_map.channels().size())
		throw std::invalid_argument(
			"SurveyBuilder::addFrame: " + std::to_string(perChannel.size()) + " channels of measurements, the map has " +
			std::to_string(m_map.channels().size()));
	if (!m_frames.empty() && m_frames.back().frame == m_lastFrame)
		throw std::logic_error("SurveyBuilder::addFrame: frame " + std::to_string(m_lastFrame) + " given twice");
	TFrame f;
	f.frame = m_lastFrame;
	f.voSegment = m_voSegment;
	f.dist = m_voDist;
	f.T_world = m_T_world_lastTracked;
	f.channels = std::move(perChannel);
	m_frames.push_back(std::move(f));
	flush(false);
}

void SurveyBuilder::finish() { flush(true); }

void SurveyBuilder::flush(bool all)
{
	const double win = m_map.options.reobservation_window_m;
	// In chain order: a keyframe is ready when the survey is past its window
	// (or out of its segment), so every frame it could see is known.
	size_t done = 0;
	for (; done < m_waiting.size(); done++)
	{
		const auto& w = m_waiting[done];
		const bool ready = all || (!m_frames.empty() && (m_frames.back().voSegment != w.voSegment ||
														   m_frames.back().dist - w.dist > win));
		if (!ready) break;
	}
	for (size_t i = 0; i < done; i++) append(std::move(m_waiting[i]));
	m_waiting.erase(m_waiting.begin(), m_waiting.begin() + static_cast<std::ptrdiff_t>(done));
	// Frames no keyframe can reach any more: not within the window of a
	// waiting keyframe, nor of one still to come (at or beyond the newest frame).
	if (m_frames.empty()) return;
	const TFrame& last = m_frames.back();
	std::vector<TFrame> keep;
	for (auto& f : m_frames)
	{
		bool need = f.voSegment == last.voSegment && last.dist - f.dist <= win;
		for (const auto& w : m_waiting) need = need || (f.voSegment == w.voSegment && std::abs(f.dist - w.dist) <= win);
		if (need || all) keep.push_back(std::move(f));
	}
	m_frames = std::move(keep);
	if (all) m_frames.clear();
}

void SurveyBuilder::append(TWaiting w)
{
	const auto& o = m_map.options;
	auto& kf = w.kf;
	const bool observed = needsFrames(), scored = scoresLandmarks();
	if (m_refined.size() < kf.channels.size()) m_refined.resize(kf.channels.size(), 0);
	for (size_t c = 0; c < kf.channels.size(); c++)
	{
		std::vector<int> score;
		std::vector<std::vector<geometry::TDepthObservation>> reobs;
		if (observed)
		{
			std::vector<TReobservingFrame> frames;
			for (const auto& f : m_frames)
				if (f.voSegment == w.voSegment && f.frame != kf.frame && std::abs(f.dist - w.dist) <= o.reobservation_window_m)
					frames.push_back({&f.channels[c], f.T_world.inverse() * w.T_world});
			reobs = findReobservations(kf.channels[c], m_map.calibration(), frames, m_matching);
			for (const auto& r : reobs) score.push_back(static_cast<int>(r.size()));
		}
		const auto idx = selectLandmarkIndices(
			kf.channels[c], o.landmarks_per_keyframe, o.selection_grid_cols, o.selection_grid_rows, m_map.imageWidth(),
			m_map.imageHeight(), scored ? &score : nullptr, o.min_reobservations);
		std::vector<features::TStereoMeasurement> kept;
		kept.reserve(idx.size());
		if (observed && m_keptSum.size() < kf.channels.size())
		{
			m_keptSum.resize(kf.channels.size(), 0);
			m_keptCount.resize(kf.channels.size(), 0);
		}
		for (size_t i : idx)
		{
			kept.push_back(kf.channels[c][i]);
			if (!observed) continue;
			m_keptSum[c] += score[i];
			m_keptCount[c] += 1;
			const double sigma_px = m_map.channels()[c].sigma_px;
			if (o.depth_from_reobservations &&
				refineDepth(kept.back(), m_map.calibration(), sigma_px, o.reobservation_sigma_px, reobs[i]))
				m_refined[c] += 1;
		}
		kf.channels[c] = std::move(kept);
	}
	m_map.appendKeyframe(std::move(kf));
}

std::vector<double> SurveyBuilder::refinedDepthShare() const
{
	std::vector<double> out;
	for (size_t c = 0; c < m_refined.size() && c < m_keptCount.size(); c++)
		out.push_back(m_keptCount[c] > 0 ? m_refined[c] / m_keptCount[c] : 0.0);
	return out;
}

std::vector<double> SurveyBuilder::meanKeptReobservations() const
{
	std::vector<double> out;
	for (size_t c = 0; c < m_keptSum.size(); c++) out.push_back(m_keptCount[c] > 0 ? m_keptSum[c] / m_keptCount[c] : 0.0);
	return out;
}

}  // namespace shadyloc::survey
