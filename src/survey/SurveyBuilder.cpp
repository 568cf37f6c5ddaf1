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

std::vector<features::TStereoMeasurement> selectLandmarks(
	const std::vector<features::TStereoMeasurement>& all, int keep, int cols, int rows, int width, int height)
{
	if (keep <= 0 || all.size() <= static_cast<size_t>(keep)) return all;
	cols = std::max(1, cols);
	rows = std::max(1, rows);
	std::vector<std::vector<size_t>> buckets(static_cast<size_t>(cols * rows));
	for (size_t i = 0; i < all.size(); i++)
	{
		const int c = std::clamp(static_cast<int>(all[i].uL * cols / std::max(1, width)), 0, cols - 1);
		const int r = std::clamp(static_cast<int>(all[i].v * rows / std::max(1, height)), 0, rows - 1);
		buckets[r * cols + c].push_back(i);
	}
	for (auto& b : buckets)
		std::stable_sort(b.begin(), b.end(), [&](size_t x, size_t y) {
			return all[x].response > all[y].response ||
				   (all[x].response == all[y].response && all[x].zncc > all[y].zncc);
		});
	std::vector<features::TStereoMeasurement> out;
	out.reserve(keep);
	for (size_t round = 0; out.size() < static_cast<size_t>(keep); round++)
	{
		bool any = false;
		for (const auto& b : buckets)
			if (round < b.size() && out.size() < static_cast<size_t>(keep))
			{
				out.push_back(all[b[round]]);
				any = true;
			}
		if (!any) break;
	}
	return out;
}

CSurveyBuilder::CSurveyBuilder(CKeyframeMap& map, const std::string& runName)
	: mrpt::system::COutputLogger("CSurveyBuilder"), m_map(map)
{
	if (map.channels().empty()) throw std::logic_error("CSurveyBuilder: set the map up (CKeyframeMap::setup) first");
	m_run = map.addRun(runName);
	if (!map.keyframes().empty()) m_segment = map.keyframes().back().segment + 1;
}

bool CSurveyBuilder::offer(
	const vo::TFrameResult& res, const std::vector<vo::TKeyframe>& voKfs, size_t voKfsBefore)
{
	m_pending.valid = false;
	if (!vo::isTracked(res.status)) return false;  // a predicted pose is no place for a keyframe
	TPending p;
	p.res = res;
	const bool restart = res.status == vo::FrameStatus::First || res.status == vo::FrameStatus::Reinit;
	if (restart)
	{
		if (voKfs.empty()) throw std::logic_error("CSurveyBuilder::offer: the VO made no keyframe at a First/Reinit frame");
		p.ref = voKfs.size() - 1;  // the frame itself
	}
	else
	{
		if (voKfsBefore == 0 || voKfsBefore > voKfs.size())
			throw std::logic_error("CSurveyBuilder::offer: inconsistent VO keyframe counts");
		p.ref = voKfsBefore - 1;  // tracked against the VO's last keyframe
		p.T_ref_f = res.T_kf_curr;
		p.cov_ref_f = res.cov_kf_curr;
	}
	if (restart || !m_segmentOpen)
	{
		p.newSegment = true;
		if (res.status == vo::FrameStatus::Reinit && m_haveOrigin) m_breaks++;
	}
	else
	{
		// T_last_f along the VO chain: inv(T_a_last) * T_a_b * T_b_f, a = last's
		// reference VO keyframe, b = this frame's.
		geometry::TPoseWithCov T = geometry::inverse({m_T_ref_last, m_cov_ref_last});
		for (size_t k = m_lastRef + 1; k <= p.ref; k++)
			T = geometry::compose(T, {voKfs[k].T_prevkf_kf, voKfs[k].cov});
		T = geometry::compose(T, {p.T_ref_f, p.cov_ref_f});
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

void CSurveyBuilder::addKeyframe(
	const std::vector<std::vector<features::TStereoMeasurement>>& perChannel,
	const std::optional<Eigen::Isometry3d>& T_gt_kf)
{
	if (!m_pending.valid) throw std::logic_error("CSurveyBuilder::addKeyframe without an accepted offer()");
	const auto& p = m_pending;
	const auto& o = m_map.options;
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
	if (p.newSegment)
	{
		if (m_segmentOpen) m_segment++;
		// After a break (or a second survey run) the segment's map pose is a
		// prediction through the VO's dead reckoning, never a measurement.
		m_predictedSegment = !m_map.keyframes().empty();
		kf.T_prev_kf = m_map.keyframes().empty() ? Eigen::Isometry3d::Identity() : m_T_map_last.inverse() * kf.T_map_kf;
		kf.cov_prev_kf = m_map.keyframes().empty() ? geometry::Matrix6d(geometry::Matrix6d::Zero()) : geometry::Matrix6d(geometry::Matrix6d::Identity() * 1e2);
	}
	else
	{
		kf.T_prev_kf = p.T_prev_f;
		kf.cov_prev_kf = p.cov_prev_f;
	}
	kf.segment = m_segment;
	kf.predicted = m_predictedSegment;
	kf.channels.resize(perChannel.size());
	for (size_t c = 0; c < perChannel.size(); c++)
		kf.channels[c] = selectLandmarks(
			perChannel[c], o.landmarks_per_keyframe, o.selection_grid_cols, o.selection_grid_rows, m_map.imageWidth(),
			m_map.imageHeight());
	m_map.appendKeyframe(std::move(kf));
	m_segmentOpen = true;
	m_lastRef = p.ref;
	m_T_ref_last = p.T_ref_f;
	m_cov_ref_last = p.cov_ref_f;
	m_T_map_last = m_map.keyframes().back().T_map_kf;
	m_pending.valid = false;
}

}  // namespace shadyloc::survey
