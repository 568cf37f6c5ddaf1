/* ShadyLoc — keyframe-based stereo VO: the composition of its stages. */
#include <shadyloc/vo/StereoVO.h>
#include <shadyloc/core/Units.h>

#include <mrpt/core/exceptions.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <stdexcept>

namespace shadyloc::vo
{
using geometry::Matrix6d;
using Clock = std::chrono::steady_clock;

namespace
{
using core::msSince;
double rotationDeg(const Eigen::Isometry3d& T)
{
	return Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI;
}
}  // namespace

std::optional<TChainReference> chainReference(
	const TFrameResult& r, const std::vector<TKeyframe>& keyframes, size_t keyframesBefore)
{
	if (!isTracked(r.status) || keyframes.empty()) return std::nullopt;
	TChainReference c;
	if (r.status == FrameStatus::First || r.status == FrameStatus::Reinit)
	{
		c.ref = keyframes.size() - 1;  // the frame itself
		return c;
	}
	if (keyframesBefore == 0 || keyframesBefore > keyframes.size()) return std::nullopt;
	c.ref = keyframesBefore - 1;  // tracked against the last keyframe before it
	c.T_ref_f = {r.T_kf_curr, r.cov_kf_curr};
	return c;
}

std::optional<geometry::TPoseWithCov> poseAlongChain(
	const std::vector<TKeyframe>& keyframes, size_t refA, const geometry::TPoseWithCov& T_refA_a, size_t refB,
	const geometry::TPoseWithCov& T_refB_b)
{
	if (refA > refB || refB >= keyframes.size()) return std::nullopt;
	geometry::TPoseWithCov T = geometry::inverse(T_refA_a);
	for (size_t k = refA + 1; k <= refB; k++)
	{
		if (keyframes[k].chain_break) return std::nullopt;
		T = geometry::compose(T, {keyframes[k].T_prevkf_kf, keyframes[k].cov});
	}
	return geometry::compose(T, T_refB_b);
}

std::string toString(FrameStatus s)
{
	switch (s)
	{
		case FrameStatus::Ok: return "ok";
		case FrameStatus::First: return "first";
		case FrameStatus::FewFeatures: return "few_features";
		case FrameStatus::FewMatches: return "few_matches";
		case FrameStatus::FewInliers: return "few_inliers";
		case FrameStatus::SolverFailed: return "solver_failed";
		case FrameStatus::WildMotion: return "wild_motion";
		case FrameStatus::Reinit: return "reinit";
	}
	return "?";
}

TKeyframeMatcherOptions matcherOptionsFrom(const TStereoVOOptions& o)
{
	TKeyframeMatcherOptions m;
	m.region = SearchRegion::Circle;
	m.search_radius_px = o.search_radius_px;
	m.search_radius_lost_px = o.search_radius_lost_px;
	m.min_matches = o.min_matches;
	m.sigma_px = o.sigma_px;
	m.max_hamming = o.max_hamming;
	m.match_ratio = o.match_ratio;
	m.refine_min_zncc = o.refine_min_zncc;
	m.refine_radius = o.refine_radius;
	m.refine_iterations = o.refine_iterations;
	m.near_min_disparity = o.near_min_disparity;
	m.near_min_matches = o.near_min_matches;
	return m;
}

TRelativePoseOptions poseEstimatorOptionsFrom(const TStereoVOOptions& o)
{
	TRelativePoseOptions p;
	p.ransac_threshold_px = o.ransac_threshold_px;
	p.ransac_iterations = o.ransac_iterations;
	p.sigma_px = o.sigma_px;
	p.huber_k = o.huber_k;
	p.two_view_ba = o.two_view_ba;
	p.ransac_prediction = o.ransac_prediction;
	p.ransac_prior_sigma_m = o.ransac_prior_sigma_m;
	p.min_inliers = o.min_inliers;
	return p;
}

TMotionKeyframePolicyOptions keyframePolicyOptionsFrom(const TStereoVOOptions& o)
{
	TMotionKeyframePolicyOptions k;
	k.kf_translation = o.kf_translation;
	k.kf_rotation_deg = o.kf_rotation_deg;
	k.kf_min_tracked_fraction = o.kf_min_tracked_fraction;
	k.kf_min_inliers = o.kf_min_inliers;
	return k;
}

// ---- the pipeline -------------------------------------------------------------
StereoVO::StereoVO(const TOptions& o, const features::TStereoFeatureOptions& fo)
	: mrpt::system::COutputLogger("StereoVO"),
	  m_opts(o),
	  m_extractor(fo),
	  m_matcher(matcherOptionsFrom(o)),
	  m_poseEstimator(poseEstimatorOptionsFrom(o)),
	  m_policy(std::make_shared<MotionKeyframePolicy>(keyframePolicyOptionsFrom(o)))
{
	m_opts.validate();
}

void StereoVO::reset()
{
	m_keyframes.clear();
	m_frame = 0;
	m_lost = 0;
	m_T_world_prev.setIdentity();
	m_velocity.setIdentity();
	m_pending = TPending();
}

void StereoVO::setKeyframePolicy(KeyframePolicy::Ptr p)
{
	ASSERTMSG_(p, "StereoVO::setKeyframePolicy: null policy");
	m_policy = std::move(p);
}

void StereoVO::addKeyframe(
	size_t frame, double timestamp, const Eigen::Isometry3d& T_world_kf, const Matrix6d& cov, bool chainBreak,
	std::vector<features::TStereoMeasurement>&& meas, const geometry::TStereoCalib& calib)
{
	TKeyframe kf;
	kf.id = static_cast<uint32_t>(m_keyframes.size());
	kf.frame = frame;
	kf.timestamp = timestamp;
	kf.T_world_kf = T_world_kf;
	kf.T_prevkf_kf =
		m_keyframes.empty() ? Eigen::Isometry3d::Identity() : m_keyframes.back().T_world_kf.inverse() * T_world_kf;
	kf.cov = cov;
	kf.chain_break = chainBreak;
	kf.meas = std::move(meas);
	m_keyframes.push_back(std::move(kf));
	m_kfCalib = calib;
}

TFrameResult StereoVO::process(
	const cv::Mat& left8, const cv::Mat& right8, const geometry::TStereoCalib& calib, double timestamp,
	const Eigen::Isometry3d* prior)
{
	track(left8, right8, calib, timestamp, prior);
	return commit(KeyframeDecision::Policy);
}

TFrameResult StereoVO::track(
	const cv::Mat& left8, const cv::Mat& right8, const geometry::TStereoCalib& calib, double timestamp,
	const Eigen::Isometry3d* prior)
{
	ASSERTMSG_(!m_pending.active, "StereoVO::track(): the previous frame was not committed (call commit())");
	const auto tStart = Clock::now();
	features::TStereoFrame fr;
	m_extractor.process(left8, right8, calib, fr);
	return trackMeasured(std::move(fr), calib, timestamp, prior, tStart);
}

TFrameResult StereoVO::track(
	features::TStereoFrame frame, const geometry::TStereoCalib& calib, double timestamp,
	const Eigen::Isometry3d* prior)
{
	ASSERTMSG_(!m_pending.active, "StereoVO::track(): the previous frame was not committed (call commit())");
	return trackMeasured(std::move(frame), calib, timestamp, prior, Clock::now());
}

TFrameResult StereoVO::trackMeasured(
	features::TStereoFrame&& fr, const geometry::TStereoCalib& calib, double timestamp,
	const Eigen::Isometry3d* prior, std::chrono::steady_clock::time_point tStart)
{
	const auto& o = m_opts;
	m_pending = TPending();
	m_pending.active = true;
	m_pending.start = tStart;
	TFrameResult res;
	res.frame = m_frame++;
	res.timestamp = timestamp;

	res.features = fr.cornersLeft;
	res.stereo = fr.meas.size();
	res.ms.detect = fr.timings.detect_ms;
	res.ms.stereo = fr.timings.stereo_ms;
	res.ms.describe = fr.timings.describe_ms;

	const Eigen::Isometry3d V =
		prior ? *prior : (o.constant_velocity ? m_velocity : Eigen::Isometry3d::Identity());
	const Eigen::Isometry3d T_world_pred = m_T_world_prev * V;

	auto finish = [&](const Eigen::Isometry3d& T_world_curr) {
		res.T_world_curr = T_world_curr;
		m_T_world_prev = T_world_curr;
		m_pending.res = res;
		return res;
	};
	// Untracked frame: predicted pose; after too many, restart a chain segment.
	auto fail = [&](FrameStatus st) {
		res.status = st;
		m_lost++;
		MRPT_LOG_THROTTLE_WARN_FMT(
			2.0, "frame %zu: %s (stereo %zu, tracked %zu, inliers %zu); predicted pose kept",
			res.frame, toString(st).c_str(), res.stereo, res.tracked, res.inliers);
		if (m_lost > o.max_lost_frames && static_cast<int>(res.stereo) >= o.min_stereo &&
			!m_keyframes.empty())
		{
			// A chain break: the link is a prediction, with a deliberately large covariance.
			const Matrix6d big = Matrix6d::Identity() * 1e2;
			addKeyframe(res.frame, timestamp, T_world_pred, big, true, std::move(fr.meas), calib);
			res.keyframe = true;
			res.status = FrameStatus::Reinit;
			res.T_kf_curr.setIdentity();
			m_lost = 0;
			m_velocity.setIdentity();
		}
		return finish(T_world_pred);
	};

	if (m_keyframes.empty())
	{
		if (static_cast<int>(res.stereo) < o.min_stereo) return fail(FrameStatus::FewFeatures);
		res.status = FrameStatus::First;
		addKeyframe(res.frame, timestamp, Eigen::Isometry3d::Identity(), Matrix6d::Zero(), false, std::move(fr.meas), calib);
		res.keyframe = true;
		m_lost = 0;
		return finish(Eigen::Isometry3d::Identity());
	}
	if (static_cast<int>(res.stereo) < o.min_stereo) return fail(FrameStatus::FewFeatures);

	// ---- matching to the keyframe (KeyframeMatcher) ------------------------------
	auto t0 = Clock::now();
	const TKeyframe& kf = m_keyframes.back();
	TKeyframeMatchInput mi;
	mi.landmarks = &kf.meas;
	mi.calib_kf = m_kfCalib;
	mi.frame = &fr;
	mi.calib = calib;
	mi.T_curr_kf_pred = T_world_pred.inverse() * kf.T_world_kf;
	mi.wide = m_lost > 0;
	TKeyframeMatchOutput mo;
	m_matcher.match(mi, mo);
	res.tracked = mo.corr.size();
	res.ms.match = msSince(t0);
	if (static_cast<int>(mo.corr.size()) < o.min_matches) return fail(FrameStatus::FewMatches);

	// ---- relative pose (RelativePoseEstimator) -------------------------------------
	TRelativePoseInput pi;
	pi.corr = &mo.corr;
	pi.calib = calib;
	pi.T_curr_ref_pred = &mi.T_curr_kf_pred;
	// The prediction spans every frame since the last tracked one.
	pi.prior_sigma_scale = 1 + m_lost;
	pi.seed = static_cast<uint32_t>(res.frame * 2654435761u + 1);
	TRelativePoseOutput po;
	m_poseEstimator.estimate(pi, po);
	res.inliers = po.inliers;
	res.ms.ransac = po.ms_ransac;
	res.ms.solve = po.ms_solve;
	if (po.status == RelativePoseStatus::FewInliers) return fail(FrameStatus::FewInliers);
	if (po.status == RelativePoseStatus::SolverFailed) return fail(FrameStatus::SolverFailed);

	const Eigen::Isometry3d T_kf_curr = po.T_curr_ref.inverse();
	const Eigen::Isometry3d T_world_curr = kf.T_world_kf * T_kf_curr;
	const Eigen::Isometry3d step = m_T_world_prev.inverse() * T_world_curr;
	if (step.translation().norm() > o.max_step_translation * (1 + m_lost) ||
		rotationDeg(step) > o.max_step_rotation_deg * (1 + m_lost))
		return fail(FrameStatus::WildMotion);

	res.status = FrameStatus::Ok;
	res.rms_px = po.rms_px;
	res.T_kf_curr = T_kf_curr;
	res.cov_kf_curr = po.cov_T_ref_curr;
	// The constant-velocity model: per-frame motion, spread over any gap.
	if (m_lost == 0)
		m_velocity = step;
	else
		m_velocity = V;
	m_lost = 0;

	TKeyframeQuery q;
	q.frame = res.frame;
	q.T_kf_curr = T_kf_curr;
	q.inliers = res.inliers;
	q.keyframe_landmarks = kf.meas.size();
	q.frames_since_keyframe = res.frame - kf.frame;
	res.keyframe_wanted = m_policy->wantKeyframe(q);
	m_pending.candidate = true;
	m_pending.meas = std::move(fr.meas);
	m_pending.calib = calib;
	return finish(T_world_curr);
}

TFrameResult StereoVO::commit(KeyframeDecision d)
{
	ASSERTMSG_(m_pending.active, "StereoVO::commit(): no tracked frame (call track() first)");
	TFrameResult& res = m_pending.res;
	if (m_pending.candidate)
	{
		const bool make = d == KeyframeDecision::Make || (d == KeyframeDecision::Policy && res.keyframe_wanted);
		if (make)
		{
			addKeyframe(res.frame, res.timestamp, res.T_world_curr, res.cov_kf_curr, false, std::move(m_pending.meas), m_pending.calib);
			res.keyframe = true;
		}
	}
	res.ms.total = msSince(m_pending.start);
	TFrameResult out = std::move(res);
	m_pending = TPending();
	return out;
}

}  // namespace shadyloc::vo
