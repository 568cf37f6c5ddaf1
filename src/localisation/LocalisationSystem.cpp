/* ShadyLoc — the combined localisation system (VO prediction, parallel
 * localisers, switching policy, global search). */
#include <shadyloc/core/Options.h>
#include <shadyloc/core/Units.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/vo/ChannelOptions.h>

#include <mrpt/core/exceptions.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <sstream>
#include <stdexcept>

namespace shadyloc::localisation
{
using geometry::Matrix6d;
using geometry::TPoseWithCov;

namespace
{
using core::kDeg;
using Clock = std::chrono::steady_clock;
using core::msSince;

Matrix6d diagCov(double sm, double sdeg)
{
	Matrix6d c = Matrix6d::Zero();
	const double sr = sdeg * kDeg;
	c.diagonal() << sm * sm, sm * sm, sm * sm, sr * sr, sr * sr, sr * sr;
	return c;
}

/** Runs a() and b() on two threads when parallel, else one after the other
 * (the results are the same either way: nothing is shared). */
template <typename A, typename B>
void both(bool parallel, A&& a, B&& b)
{
	if (!parallel)
	{
		a();
		b();
		return;
	}
	auto f = std::async(std::launch::async, std::forward<B>(b));
	std::exception_ptr ea;
	try
	{
		a();
	}
	catch (...)
	{
		ea = std::current_exception();
	}
	f.get();  // rethrows b's exception
	if (ea) std::rethrow_exception(ea);
}
}  // namespace

// ---- options -----------------------------------------------------------------------
void TSystemOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	// A system key for one stop; whether places seed is each localiser's now.
	v.renamed({{"seed_with_places", "place_seeds_search", "[localiser] or [localiser.<channel>]"}});
	v("localisers", localisers, "", Range::any(), "policy order: the first with an accepted fix is used");
	v("joint", joint, "", Range::any(),
	  "channels whose searches one more localiser solves together, first in policy order (empty = none; runs "
	  "only when each is a localiser)");
	v("joint_only_where_a_channel_fails", joint_only_where_a_channel_fails, "", Range::any(),
	  "... only on frames where one of its channels' localisers has no accepted fix (elsewhere theirs are used)");
	v.choice("joint_patch_matches", joint_patch_matches,
			 {{"all", JointPatchMatches::All}, {"of_fixes", JointPatchMatches::OfFixes}, {"none", JointPatchMatches::None}},
			 "all | of_fixes | none: a channel's patch-pass matches the joint localiser takes (of_fixes: where its solve "
			 "was accepted)");
	v("vo_channel", vo_channel, "", Range::any(), "the live VO that predicts for every localiser");
	v("vo_fallback_channel", vo_fallback_channel, "", Range::any(),
	  "a second live VO whose step is used where vo_channel's could not be measured (\"\" = none; runs only "
	  "when the channel is a localiser)");
	v("threads", threads, "", Range::atLeast(1), "");
	v("vo_cov_scale", vo_cov_scale, "", Range::atLeast(1), "");
	v("vo_lost_sigma_m", vo_lost_sigma_m, "m", Range::above(0), "");
	v("vo_lost_sigma_deg", vo_lost_sigma_deg, "deg", Range::above(0), "");
	v("vo_sigma_m_per_m", track.drift_m_per_m, "m/m", Range::atLeast(0), "drift: sigma per metre since the last fix");
	v("vo_sigma_deg_per_m", track.drift_deg_per_m, "deg/m", Range::atLeast(0), "");
	v("confirmed_max_sigma_m", track.confirmed_max_sigma_m, "m", Range::above(0),
	  "the track is a confirmed place while sigma is below");
	v("relocalise_after_frames", track.relocalise_after_frames, "frames", Range::atLeast(1),
	  "without a fix this long, search around dead reckoning");
	v("relocalise_window_m", track.relocalise_window_m, "m", Range::above(0),
	  "... this far along the chain on both sides, and as near in the map frame");
	v("relocalise_max_angle_deg", track.relocalise_max_angle_deg, "deg", Range::openClosed(0, 180),
	  "... a keyframe of another segment facing within this");
	v("relocalise_at_dead_reckoning", track.relocalise_at_dead_reckoning, "", Range::any(),
	  "... first matching each candidate where dead reckoning projects it, warped");
	v("fuse_prediction", track.fuse_prediction, "", Range::any(),
	  "while the track is confirmed, a fix is the solve fused with the prediction");
	v("cross_check_fixes", track.cross_check_fixes, "", Range::any(),
	  "where the localisers' fixes of a frame disagree, the most certain is used");
	v.choice("reject_contradicted", track.reject_contradicted,
			 {{"none", TTrackOptions::Contradicted::Kept},
			  {"joint", TTrackOptions::Contradicted::Joint},
			  {"all", TTrackOptions::Contradicted::All}},
			 "none | joint | all: whose fix that disagrees with a more certain one of the frame is no fix");
	v("confirmed_track_outranks_places", track.confirmed_track_outranks_places, "", Range::any(),
	  "a place that is no fix replaces a confirmed track only when the more certain");
	v("global_search_after_frames", track.global_search_after_frames, "frames", Range::any(),
	  "... and the whole map after this");
	v("global_keyframes_per_frame", track.global_keyframes_per_frame, "keyframes", Range::atLeast(0),
	  "... at most this many keyframes a frame, the next slice of the map each time (0: the whole map)");
	v("seed_with_unconfirmed", track.seed_with_unconfirmed, "", Range::any(),
	  "a consistent but unconfirmed solve narrows the next search (never a fix, never validates)");
	v("global_sigma_m", track.global_sigma_m, "m", Range::atLeast(0), "");
	v("global_sigma_deg", track.global_sigma_deg, "deg", Range::atLeast(0), "");
}

void TSystemOptions::load(const mrpt::config::CConfigFileBase& c, const std::string& s) { core::loadKeys(*this, c, s); }

void TSystemOptions::dump(std::ostream& out) const { core::dumpKeys(*this, out); }

void TSystemOptions::validate() const
{
	auto need = [](bool ok, const char* key, const char* what) {
		if (!ok) throw std::invalid_argument(std::string(key) + ": " + what);
	};
	need(!localisers.empty(), "localisers", "names no localiser (mono, invariant, ...)");
	for (size_t i = 0; i < localisers.size(); i++)
		for (size_t j = i + 1; j < localisers.size(); j++)
			need(localisers[i] != localisers[j], "localisers", "a localiser named twice");
	for (size_t i = 0; i < joint.size(); i++)
		for (size_t j = i + 1; j < joint.size(); j++) need(joint[i] != joint[j], "joint", "a channel named twice");
	need(joint.empty() || joint.size() >= 2, "joint", "names one channel: a joint solve needs two or more");
	need(!vo_channel.empty(), "vo_channel", "must name a channel");
	need(vo_fallback_channel != vo_channel, "vo_fallback_channel", "must differ from vo_channel (or be empty)");
	core::checkKeys(*this);
	need(track.global_search_after_frames >= track.relocalise_after_frames, "global_search_after_frames",
		 "must be >= relocalise_after_frames");
}

// ---- the update ------------------------------------------------------------------------
const TLocaliserResult* TLocalisationUpdate::result(const std::string& channel) const
{
	for (const auto& r : localisers)
		if (r.channel == channel) return &r;
	return nullptr;
}

mrpt::poses::CPose3DPDFGaussian TLocalisationUpdate::pdf() const
{
	TPoseWithCov p;
	p.T = T_kf_live;
	p.cov = cov;
	return geometry::toCPose3DPDFGaussian(p);
}

// ---- the system ----------------------------------------------------------------------------
namespace
{
features::TStereoFeatureOptions featuresOf(
	const std::vector<LocalisationSystem::TChannelSetup>& channels, const std::string& label)
{
	for (const auto& c : channels)
		if (c.channel.label == label) return c.features;
	throw std::invalid_argument("LocalisationSystem: no channel '" + label + "' given (the VO's channel)");
}
}  // namespace

LocalisationSystem::LocalisationSystem(
	CKeyframeMap::Ptr map, const std::vector<TChannelSetup>& channels, const vo::TStereoVOOptions& vopt,
	const TSystemOptions& o, const std::optional<vo::TStereoVOOptions>& voFallback,
	const std::optional<TLocaliserOptions>& joint)
	: mrpt::system::COutputLogger("LocalisationSystem"),
	  m_map(std::move(map)),
	  m_opts(o),
	  // The VO runs on the VO channel's shared measurements (track() with a
	  // measured frame): its own extractor only holds the options.
	  m_vo(vopt, featuresOf(channels, o.vo_channel)),
	  m_track(o.track),
	  m_sweep(0, 0)
{
	m_opts.validate();
	if (!m_map) throw std::invalid_argument("LocalisationSystem: no map");
	m_sweep = MapSweep(m_map->keyframeCount(), m_opts.track.global_keyframes_per_frame);
	if (m_map->isEmpty()) throw std::invalid_argument("LocalisationSystem: the map has no keyframes");
	auto find = [&](const std::string& l) -> const TChannelSetup* {
		for (const auto& c : channels)
			if (c.channel.label == l) return &c;
		return nullptr;
	};
	std::vector<std::string> labels = {m_opts.vo_channel};
	for (const auto& l : m_opts.localisers)
		if (l != m_opts.vo_channel) labels.push_back(l);
	for (const auto& l : labels)
	{
		const TChannelSetup* c = find(l);
		if (!c) throw std::invalid_argument("LocalisationSystem: no channel '" + l + "' given");
		TPipe p{*c, features::StereoFeatureExtractor(c->features), nullptr, -1};
		const auto it = std::find(m_opts.localisers.begin(), m_opts.localisers.end(), l);
		if (it != m_opts.localisers.end())
		{
			p.policyRank = static_cast<int>(it - m_opts.localisers.begin());
			// Throws naming the map's channels when it has no such channel.
			p.localiser = std::make_unique<StereoLocaliser>(*m_map, l, c->localiser);
			m_map->checkCompatible(liveParams(c->channel, c->features));
		}
		m_pipes.push_back(std::move(p));
	}
	m_vo.vo.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	if (voFallback && !m_opts.vo_fallback_channel.empty())
		for (size_t i = 1; i < m_pipes.size(); i++)
			if (m_pipes[i].setup.channel.label == m_opts.vo_fallback_channel && m_pipes[i].localiser)
			{
				m_voFallback = std::make_unique<TVOTrack>(*voFallback, m_pipes[i].setup.features);
				m_voFallback->pipe = i;
				m_voFallback->vo.setMinLoggingLevel(mrpt::system::LVL_ERROR);
			}
	// The joint localiser runs beside all of its channels' localisers, or not at all.
	if (joint && !m_opts.joint.empty())
	{
		std::vector<size_t> pipes;
		for (const auto& l : m_opts.joint)
			for (size_t i = 0; i < m_pipes.size(); i++)
				if (m_pipes[i].setup.channel.label == l && m_pipes[i].localiser) pipes.push_back(i);
		if (pipes.size() == m_opts.joint.size())
		{
			m_joint = std::make_unique<JointLocaliser>(*m_map, m_opts.joint, *joint, m_opts.threads);
			m_jointPipes = pipes;
		}
	}
}

map::TChannelParams LocalisationSystem::liveParams(const filters::TChannel& ch, const features::TStereoFeatureOptions& fo)
{
	// What the survey records for a channel (survey::channelParams): the filter and the features.
	return map::TChannelParams::From(ch.label, ch.filter->GetRuntimeClass()->className, ch.filter->imageOptionsAsIni(), fo);
}

map::TChannelParams LocalisationSystem::liveParams(const std::string& label) const
{
	const auto& s = channelSetup(label);
	return liveParams(s.channel, s.features);
}

std::vector<std::string> LocalisationSystem::channelLabels() const
{
	std::vector<std::string> l;
	for (const auto& p : m_pipes) l.push_back(p.setup.channel.label);
	return l;
}

const LocalisationSystem::TChannelSetup& LocalisationSystem::channelSetup(const std::string& label) const
{
	for (const auto& p : m_pipes)
		if (p.setup.channel.label == label) return p.setup;
	throw std::out_of_range("LocalisationSystem: no channel '" + label + "'");
}

LocalisationSystem::TSetup LocalisationSystem::SetupFromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::vector<std::string>& localisers, int threads,
	const std::string& what)
{
	TSetup r;
	TSystemOptions& so = r.system;
	if (cfg.sectionExists("localise")) so.load(cfg, "localise");
	if (!localisers.empty()) so.localisers = localisers;
	if (threads > 0) so.threads = threads;
	so.validate();
	std::vector<std::string> labels = {so.vo_channel};
	for (const auto& l : so.localisers)
		if (l != so.vo_channel) labels.push_back(l);
	std::vector<TChannelSetup>& chans = r.channels;
	for (const auto& l : labels)
	{
		TChannelSetup c;
		c.channel = filters::channelFromConfig(cfg, l, what);
		// The channel's name as the map knows it (the config may call it by its suffix).
		c.features = vo::featureOptionsFor(cfg, c.channel.label);
		c.localiser = localiserOptionsFor(cfg, c.channel.label);
		chans.push_back(std::move(c));
	}
	// Localisers named by a suffix ("inv") take the channel's label.
	for (size_t i = 0; i < labels.size(); i++)
	{
		for (auto& l : so.localisers)
			if (l == labels[i]) l = chans[i].channel.label;
		if (so.vo_channel == labels[i]) so.vo_channel = chans[i].channel.label;
		if (so.vo_fallback_channel == labels[i]) so.vo_fallback_channel = chans[i].channel.label;
		for (auto& l : so.joint)
			if (l == labels[i]) l = chans[i].channel.label;
	}
	r.vo = vo::voOptionsFor(cfg, so.vo_channel);
	// The fallback VO runs only beside its channel's localiser: the baseline
	// (`--localisers mono`) stays the paper's baseline alone.
	if (!so.vo_fallback_channel.empty() &&
		std::find(so.localisers.begin(), so.localisers.end(), so.vo_fallback_channel) != so.localisers.end())
		r.voFallback = vo::voOptionsFor(cfg, so.vo_fallback_channel);
	const bool jointRuns = !so.joint.empty() && std::all_of(so.joint.begin(), so.joint.end(), [&](const std::string& j) {
		return std::find(so.localisers.begin(), so.localisers.end(), j) != so.localisers.end();
	});
	if (jointRuns)
	{
		r.joint = localiserOptionsFor(cfg, JointLocaliser::kLabel);
		r.joint->validate();
	}
	return r;
}

std::unique_ptr<LocalisationSystem> LocalisationSystem::FromConfig(
	const mrpt::config::CConfigFileBase& cfg, CKeyframeMap::Ptr map, const std::vector<std::string>& localisers,
	int threads, const std::string& what)
{
	TSetup s = SetupFromConfig(cfg, localisers, threads, what);
	return std::make_unique<LocalisationSystem>(std::move(map), s.channels, s.vo, s.system, s.voFallback, s.joint);
}

void LocalisationSystem::reset()
{
	for (TVOTrack* t : {&m_vo, m_voFallback.get()})
		if (t)
		{
			t->vo.reset();
			t->havePrev = false;
			t->standby.reset();
			t->trackedLast = false;
		}
	m_lastVoStep.reset();
	for (auto& p : m_pipes)
		if (p.localiser) p.localiser->reset();
	if (m_joint) m_joint->reset();
	m_frame = 0;
	m_track.reset();
	m_searchAmong.clear();
	m_sweep.restart();
	m_distance = 0;
}

void LocalisationSystem::setStartKeyframe(uint32_t id, double radius)
{
	m_map->keyframe(id);  // throws naming the id
	m_track.reset();
	m_searchAmong = m_map->keyframesAlongChain(id, radius, radius);
}

TMotion LocalisationSystem::motionOf(const vo::TFrameResult& r, TVOTrack& t, bool& measured) const
{
	TMotion m;
	measured = false;
	const bool havePrev = t.havePrev;
	const vo::TFrameResult prevVO = std::move(t.prev);
	t.prev = r;
	t.havePrev = true;
	if (!havePrev) return m;  // the first frame: no motion
	m.valid = true;
	m.T_prev_curr = prevVO.T_world_curr.inverse() * r.T_world_curr;
	measured = r.status == vo::FrameStatus::Ok && (prevVO.keyframe || prevVO.status == vo::FrameStatus::Ok);
	if (measured)
	{
		TPoseWithCov cur;
		cur.T = r.T_kf_curr;
		cur.cov = r.cov_kf_curr;
		if (prevVO.keyframe)
			m.cov = cur.cov;  // the previous frame is this frame's reference keyframe
		else
		{
			// Both relative to the same keyframe: T_prev_curr = T_kf_prev^-1 T_kf_curr,
			// errors taken as independent (conservative: they share the keyframe's).
			TPoseWithCov prev;
			prev.T = prevVO.T_kf_curr;
			prev.cov = prevVO.cov_kf_curr;
			m.cov = geometry::compose(geometry::inverse(prev), cur).cov;
		}
		m.cov *= m_opts.vo_cov_scale;
	}
	else
		m.cov = diagCov(m_opts.vo_lost_sigma_m, m_opts.vo_lost_sigma_deg);
	return m;  // drift since the last fix: Track::predict
}

TLocalisationUpdate LocalisationSystem::processObservation(const mrpt::obs::CObservationStereoImages& obs)
{
	if (!obs.hasImageRight)
		throw std::invalid_argument("LocalisationSystem: observation '" + obs.sensorLabel + "' has no right image");
	const cv::Mat l = obs.imageLeft.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY);
	const cv::Mat r = obs.imageRight.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY);
	return processFrame(l, r, geometry::TStereoCalib::FromObservation(obs), mrpt::Clock::toDouble(obs.timestamp));
}

void LocalisationSystem::extractChannel(
	size_t i, const ChannelImages& images, const geometry::TStereoCalib& calib, size_t frame,
	std::vector<features::TStereoFrame>& meas, std::vector<double>& msConvert)
{
	const auto t0 = Clock::now();
	cv::Mat gl, gr;
	try
	{
		images(i, gl, gr);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(
			"frame " + std::to_string(frame) + ": channel '" + m_pipes[i].setup.channel.label + "': " + e.what());
	}
	if (gl.type() != CV_8UC1)
		throw std::runtime_error(
			"frame " + std::to_string(frame) + ": channel '" + m_pipes[i].setup.channel.label + "' does not give grey images");
	msConvert[i] = msSince(t0);
	m_pipes[i].extractor.process(gl, gr, calib, meas[i]);
}

bool LocalisationSystem::voMotion(
	const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib, double timestamp,
	TLocalisationUpdate& u)
{
	m_vo.vo.track(meas[0], calib, timestamp);
	u.vo = m_vo.vo.commit();
	bool measured = false;
	u.motion = motionOf(u.vo, m_vo, measured);
	if (u.motion.valid) u.motion_from = m_pipes[0].setup.channel.label;
	if (measured) m_lastVoStep = u.motion.T_prev_curr;
	return measured;
}

void LocalisationSystem::fallbackMotion(
	const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib, double timestamp,
	bool voMeasured, TLocalisationUpdate& u)
{
	TVOTrack& fb = *m_voFallback;
	const features::TStereoFrame& mine = meas[fb.pipe];
	if (voMeasured)
	{
		// Not needed: this frame becomes its standby at the frame's end.
		fb.trackedLast = false;
		return;
	}
	const Eigen::Isometry3d* prior = nullptr;
	if (!fb.trackedLast)
	{
		// Needed from this frame on: the frame before is its keyframe, and
		// the VO channel's last measured step predicts this one.
		fb.vo.reset();
		fb.havePrev = false;
		if (fb.standby)
		{
			fb.vo.track(std::move(fb.standby->meas), fb.standby->calib, fb.standby->timestamp);
			bool unused = false;
			(void)motionOf(fb.vo.commit(), fb, unused);
		}
		if (m_lastVoStep) prior = &*m_lastVoStep;
	}
	fb.standby.reset();
	fb.trackedLast = true;
	fb.vo.track(mine, calib, timestamp, prior);
	u.vo_fallback = fb.vo.commit();
	bool measured = false;
	TMotion f = motionOf(u.vo_fallback, fb, measured);
	if (measured)
	{
		u.motion = f;
		u.motion_from = m_pipes[fb.pipe].setup.channel.label;
	}
}

TLocaliserInput LocalisationSystem::predict(const geometry::TStereoCalib& calib, double timestamp, TLocalisationUpdate& u)
{
	if (u.motion.valid) m_distance += u.motion.T_prev_curr.translation().norm();
	u.distance_m = m_distance;
	TLocaliserInput in;
	in.frame = u.frame;
	in.timestamp = timestamp;
	in.calib = calib;
	in.prediction = m_track.predict(u.motion);	// the track composed with VO's step
	in.search = m_track.searchSeed();
	in.track_confirmed = u.track_confirmed = m_track.confirmed();
	in.motion = u.motion;
	return in;
}

TLocaliserInput LocalisationSystem::frontEndThenLocalisers(
	const ChannelImages& images, const geometry::TStereoCalib& calib, double timestamp,
	std::vector<features::TStereoFrame>& meas, TLocalisationUpdate& u, const LocaliseChannel& localise)
{
	const size_t n = m_pipes.size();
	std::vector<double> msConv(n, 0);
	const auto t0 = Clock::now();
	for (size_t i = 0; i < n; i++) extractChannel(i, images, calib, u.frame, meas, msConv);
	const bool measured = voMotion(meas, calib, timestamp, u);
	if (m_voFallback) fallbackMotion(meas, calib, timestamp, measured, u);
	for (const double c : msConv) u.ms_convert += c;
	u.ms_front_end = msSince(t0);
	const TLocaliserInput in = predict(calib, timestamp, u);
	for (size_t i = 0; i < n; i++)
		if (m_pipes[i].localiser) localise(i, in);
	return in;
}

TLocaliserInput LocalisationSystem::frontEndOverlappingLocalisers(
	const ChannelImages& images, const geometry::TStereoCalib& calib, double timestamp,
	std::vector<features::TStereoFrame>& meas, TLocalisationUpdate& u, const LocaliseChannel& localise)
{
	// Thread 1: the VO channel's features and VO, the prediction, its
	// localiser. Thread 2: the other channels' features, then (once the
	// prediction is made) their localisers. The fallback VO, whose step is
	// needed only where the VO channel's was not measured, runs before the
	// prediction then; else its standby is kept after thread 1's localiser.
	// The same work as one thread does in order, so the same results.
	const size_t n = m_pipes.size();
	std::vector<double> msConv(n, 0), frontEndEnd(2, 0), doneAt(2, 0);
	const auto t0 = Clock::now();
	std::promise<void> othersExtracted, predicted;
	std::future<void> othersReady = othersExtracted.get_future(), prediction = predicted.get_future();
	TLocaliserInput in;
	auto first = [&] {
		bool inputReady = false;
		try
		{
			extractChannel(0, images, calib, u.frame, meas, msConv);
			const bool measured = voMotion(meas, calib, timestamp, u);
			frontEndEnd[0] = msSince(t0);
			const bool fallbackFirst = m_voFallback && !measured;
			if (fallbackFirst)
			{
				othersReady.get();
				fallbackMotion(meas, calib, timestamp, measured, u);
			}
			in = predict(calib, timestamp, u);
			inputReady = true;
			predicted.set_value();
			if (m_pipes[0].localiser) localise(0, in);
			if (m_voFallback && !fallbackFirst)
			{
				othersReady.get();
				fallbackMotion(meas, calib, timestamp, measured, u);
			}
			doneAt[0] = msSince(t0);
		}
		catch (...)
		{
			if (!inputReady) predicted.set_exception(std::current_exception());
			throw;
		}
	};
	auto others = [&] {
		try
		{
			for (size_t i = 1; i < n; i++) extractChannel(i, images, calib, u.frame, meas, msConv);
			frontEndEnd[1] = msSince(t0);
			othersExtracted.set_value();
		}
		catch (...)
		{
			othersExtracted.set_exception(std::current_exception());
			throw;
		}
		prediction.get();  // rethrows the first thread's failure
		for (size_t i = 1; i < n; i++)
			if (m_pipes[i].localiser) localise(i, in);
		doneAt[1] = msSince(t0);
	};
	both(true, first, others);
	u.ms_wait = std::abs(doneAt[0] - doneAt[1]);
	for (const double c : msConv) u.ms_convert += c;
	u.ms_front_end = std::max(frontEndEnd[0], frontEndEnd[1]);
	return in;
}

template <typename F>
void LocalisationSystem::forLocalisers(F&& fn)
{
	const bool par = m_opts.threads >= 2 && m_pipes.size() >= 2;
	auto runFirst = [&] {
		if (m_pipes[0].localiser) fn(size_t(0));
	};
	auto runRest = [&] {
		for (size_t i = 1; i < m_pipes.size(); i++)
			if (m_pipes[i].localiser) fn(i);
	};
	both(par, runFirst, runRest);
}

const TLocaliserResult* LocalisationSystem::policyFix(const std::vector<const TLocaliserResult*>& inOrder) const
{
	std::vector<const TLocaliserResult*> accepted;
	for (const auto* r : inOrder)
		if (r->accepted()) accepted.push_back(r);
	if (accepted.empty()) return nullptr;
	if (!m_opts.track.cross_check_fixes || accepted.size() < 2) return accepted.front();
	std::vector<TKeyframePose> fixes;
	std::vector<double> sigma;
	for (const auto* r : accepted)
	{
		fixes.push_back(r->pose());
		sigma.push_back(r->sigma_m);
	}
	// The first accepted localiser's link and prediction test judge.
	const auto [link, chi2] = comparisonOf(*accepted.front());
	const size_t k = chooseFix(fixes, sigma, link, chi2);
	if (k != 0)
		MRPT_LOG_DEBUG_FMT(
			"frame %zu: the fixes disagree; %s (sigma %.3f m) used, not %s (%.3f m)", accepted[k]->frame,
			accepted[k]->channel.c_str(), sigma[k], accepted.front()->channel.c_str(), sigma.front());
	return accepted[k];
}

std::pair<KeyframeLink, double> LocalisationSystem::comparisonOf(const TLocaliserResult& r) const
{
	if (m_joint && r.channel == JointLocaliser::kLabel)
		return {[this](uint32_t a, uint32_t b) { return m_joint->between(a, b); }, m_joint->options().prediction_chi2};
	const StereoLocaliser* L = localiser(r.channel);
	return {[L](uint32_t a, uint32_t b) { return L->between(a, b); }, L->options().prediction_chi2};
}

void LocalisationSystem::rejectContradicted(std::vector<TLocaliserResult>& results)
{
	std::vector<TLocaliserResult*> accepted;
	std::vector<TKeyframePose> fixes;
	std::vector<double> sigma;
	for (auto& r : results)
		if (r.accepted())
		{
			accepted.push_back(&r);
			fixes.push_back(r.pose());
			sigma.push_back(r.sigma_m);
		}
	if (accepted.size() < 2) return;
	const auto [link, chi2] = comparisonOf(*accepted.front());
	const std::vector<bool> contradicted = contradictedFixes(fixes, sigma, link, chi2);
	for (size_t i = 0; i < accepted.size(); i++)
	{
		TLocaliserResult& r = *accepted[i];
		const bool joint = r.channel == JointLocaliser::kLabel;
		if (!contradicted[i] || (m_opts.track.reject_contradicted == TTrackOptions::Contradicted::Joint && !joint))
			continue;
		r.status = LocaliserStatus::Contradicted;
		r.consistent = 0;
		if (joint)
			m_joint->forgetSolve();
		else
			for (auto& p : m_pipes)
				if (p.localiser && p.setup.channel.label == r.channel) p.localiser->forgetSolve();
		MRPT_LOG_DEBUG_FMT("frame %zu: the %s fix (sigma %.3f m) contradicts a more certain one", r.frame, r.channel.c_str(), r.sigma_m);
	}
}

TKeyframePose LocalisationSystem::fusedFix(const TLocaliserResult& r, const TKeyframePose& pred, bool confirmed) const
{
	TKeyframePose f = r.pose();
	// Only a prediction made of accepted fixes, linked by measurements.
	if (!m_opts.track.fuse_prediction || !confirmed || !pred.valid || !m_map->sameSegment(f.kf, pred.kf)) return f;
	geometry::TPoseWithCov p = pred.withCov();
	if (pred.kf != f.kf)
	{
		const auto link = m_map->relativePose(f.kf, pred.kf);
		p = geometry::compose({link.T_a_b, link.cov}, p);
	}
	const auto fused = fuseWithPrediction(f.withCov(), p);
	f.T_kf_live = fused.T;
	f.cov = fused.cov;
	return f;
}

std::vector<uint32_t> keyframesAroundDeadReckoning(
	const CKeyframeMap& map, const TKeyframePose& deadReckoning, double window_m, double max_angle_deg)
{
	std::vector<uint32_t> among = map.keyframesAlongChain(deadReckoning.kf, window_m, window_m);
	// At a VO break of the survey the chain ends but the road goes on in
	// another segment, whose map pose is the survey's dead reckoning: also
	// every keyframe that near the dead-reckoned camera in the map frame.
	map::TNearestQuery q;
	q.max_distance_m = window_m;
	q.max_angle_deg = max_angle_deg;
	q.max_results = map.keyframeCount();
	q.same_frame_as = deadReckoning.kf;
	const Eigen::Isometry3d T_map_live = map.keyframe(deadReckoning.kf).T_map_kf * deadReckoning.T_kf_live;
	for (const auto& h : map.nearestKeyframes(T_map_live, q))
		if (std::find(among.begin(), among.end(), h.id) == among.end()) among.push_back(h.id);
	std::sort(among.begin(), among.end());
	return among;
}

void LocalisationSystem::searchPlace(
	SearchScope scope, const std::vector<features::TStereoFrame>& meas, const geometry::TStereoCalib& calib,
	const std::vector<size_t>& order, TLocalisationUpdate& u)
{
	std::vector<uint32_t> among = m_searchAmong;
	std::optional<Eigen::Isometry3d> guess;	 // dead reckoning in the map frame
	if (scope == SearchScope::Window && m_track.estimate().valid)
	{
		const TKeyframePose& dr = m_track.estimate();
		among = keyframesAroundDeadReckoning(
			*m_map, dr, m_opts.track.relocalise_window_m, m_opts.track.relocalise_max_angle_deg);
		// A confirmed track's, or a hypothesis' that began at a verified place.
		if (m_opts.track.relocalise_at_dead_reckoning && (m_track.confirmed() || m_track.hypothesisPlaces() >= 1))
			guess = m_map->keyframe(dr.kf).T_map_kf * dr.T_kf_live;
	}
	else if (among.empty())
		among = m_sweep.next();
	const auto seed = static_cast<uint32_t>(u.frame * 7919u + 3);
	std::vector<TGlobalPlace> places(m_pipes.size());
	std::vector<double> ms(m_pipes.size(), 0);
	forLocalisers([&](size_t i) {
		const auto t0 = Clock::now();
		const auto& L = *m_pipes[i].localiser;
		places[i] = among.empty() ? L.globalSearch(meas[i], calib, seed) : L.globalSearch(meas[i], calib, seed, among, guess);
		ms[i] = msSince(t0);
	});
	u.global_search = true;
	u.search_scope = scope;
	u.place = places[order.front()];
	for (size_t k = 0; k < order.size(); k++) u.localisers[k].ms += ms[order[k]];
	for (const size_t i : order)
		if (places[i].ok)
		{
			u.place = places[i];
			// Two verified places that agree through VO confirm the place as K
			// consistent frames of the localisers would; a place that
			// replaced the hypothesis instead would restart it on every search.
			// Through the localiser's link, which crosses a VO break of the map
			// (the place may lie in another segment than the track).
			const auto& L = *m_pipes[i].localiser;
			const KeyframeLink link = [&L](uint32_t a, uint32_t b) { return L.between(a, b); };
			const auto& lo = L.options();
			const TKeyframePose& place = places[i].pose;
			const PlaceTest agreesWith = [&](const TKeyframePose& pred) {
				return placeAgrees(place, pred, link, lo.prediction_chi2);
			};
			const PlaceOutcome outcome =
				m_track.placeFound(place, agreesWith, places[i].certain, lo.consistent_frames, lo.place_seeds_search);
			if (outcome == PlaceOutcome::Fix) u.used = m_pipes[i].setup.channel.label;
			// The verified place is each localiser's first consistent frame
			// (unless the track outranked it).
			if (outcome != PlaceOutcome::Outranked)
			{
				for (const size_t j : order) m_pipes[j].localiser->startFrom(u.frame, m_track.estimate());
				if (m_joint) m_joint->startFrom(u.frame, m_track.estimate());
			}
			m_searchAmong.clear();
			MRPT_LOG_DEBUG_FMT(
				"frame %zu: place found by %s at keyframe %u (%d inliers)%s", u.frame,
				m_pipes[i].setup.channel.label.c_str(), places[i].pose.kf, places[i].inliers,
				outcome == PlaceOutcome::Outranked ? ", outranked by the confirmed track" : "");
			return;
		}
}

TLocalisationUpdate LocalisationSystem::processFrame(
	const cv::Mat& left, const cv::Mat& right, const geometry::TStereoCalib& calib, double timestamp)
{
	// Each channel made from the colour pair on the thread that extracts it.
	return processChannels(
		[&](size_t i, cv::Mat& l, cv::Mat& r) { m_pipes[i].setup.channel.convertPair(left, right, l, r); }, calib,
		timestamp);
}

TLocalisationUpdate LocalisationSystem::processChannels(
	const ChannelImages& images, const geometry::TStereoCalib& calib, double timestamp)
{
	TLocalisationUpdate u;
	u.frame = m_frame++;
	u.timestamp = timestamp;
	const size_t n = m_pipes.size();
	const auto tAll = Clock::now();
	std::vector<features::TStereoFrame> meas(n);

	// ---- the front end, the predictor and the localisers (no prediction:
	// each records a failure)
	std::vector<TLocaliserResult> res(n);
	std::vector<TSearchedCorrespondences> searched(m_joint ? n : 0);
	const LocaliseChannel localise = [&](size_t i, const TLocaliserInput& in) {
		TLocaliserInput mine = in;
		mine.meas = &meas[i];
		res[i] = m_pipes[i].localiser->localise(mine, m_joint ? &searched[i] : nullptr);
	};
	const bool parallel = m_opts.threads >= 2 && n >= 2;
	const TLocaliserInput in = parallel ? frontEndOverlappingLocalisers(images, calib, timestamp, meas, u, localise)
										: frontEndThenLocalisers(images, calib, timestamp, meas, u, localise);
	const TKeyframePose& pred = in.prediction;
	std::vector<size_t> order;	// the channel localisers in policy order
	for (size_t i = 0; i < n; i++)
		if (m_pipes[i].localiser) order.push_back(i);
	std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return m_pipes[a].policyRank < m_pipes[b].policyRank; });
	for (const size_t i : order) u.localisers.push_back(res[i]);
	// ---- the joint localiser on what their searches found (after them in
	// the update, first in policy order)
	std::vector<const TLocaliserResult*> inOrder;
	const bool jointRuns =
		m_joint && !(m_opts.joint_only_where_a_channel_fails &&
					 std::all_of(m_jointPipes.begin(), m_jointPipes.end(), [&](size_t i) { return res[i].accepted(); }));
	if (m_joint)
	{
		std::vector<const TSearchedCorrespondences*> parts;
		for (const size_t i : m_jointPipes)
		{
			keepJointShare(searched[i], res[i].accepted(), m_opts.joint_patch_matches);
			parts.push_back(&searched[i]);
		}
		u.localisers.push_back(jointRuns ? m_joint->localise(in, parts) : m_joint->notRun(in));
		inOrder.push_back(&u.localisers.back());
	}
	for (size_t k = 0; k < order.size(); k++) inOrder.push_back(&u.localisers[k]);
	if (m_opts.track.reject_contradicted != TTrackOptions::Contradicted::Kept) rejectContradicted(u.localisers);

	// ---- the policy: the first accepted fix in policy order (the most certain
	// where they disagree), else dead reckoning
	const TLocaliserResult* fix = policyFix(inOrder);
	if (fix)
	{
		u.used = fix->channel;
		m_track.fix(fusedFix(*fix, pred, u.track_confirmed));
		// Not run: its next solve is motion-tested against the system's fix
		// (an accepted one, never a seed of its own).
		if (m_joint && !jointRuns) m_joint->startFrom(u.frame, m_track.estimate());
	}
	else
	{
		std::vector<TKeyframePose> seeds;
		bool allLost = true;
		for (const size_t i : order)
		{
			allLost &= res[i].status == LocaliserStatus::Lost;
			if (res[i].status == LocaliserStatus::Unconfirmed) seeds.push_back(res[i].pose());
		}
		if (m_joint && u.localisers.back().status == LocaliserStatus::Unconfirmed) seeds.push_back(u.localisers.back().pose());
		m_track.noFix(seeds);
		// ---- relocalisation, on this frame
		const SearchScope scope = m_track.searchNeeded(allLost);
		if (scope != SearchScope::None)
		{
			const auto tSearch = Clock::now();
			searchPlace(scope, meas, calib, order, u);
			u.ms_relocalise = msSince(tSearch);
		}
	}
	u.frames_since_fix = m_track.framesSinceFix();
	const TKeyframePose& shown = m_track.estimate();
	if (shown.valid)
	{
		const auto& kf = m_map->keyframe(shown.kf);
		u.placeKnown = true;
		u.kf_id = kf.id;
		u.kf_run = kf.run;
		u.kf_frame = kf.frame;
		u.kf_stamp = kf.timestamp;
		u.T_kf_live = shown.T_kf_live;
		u.cov = shown.cov;
		u.T_map_live = kf.T_map_kf * shown.T_kf_live;
	}
	if (getMinLoggingLevel() <= mrpt::system::LVL_DEBUG)
		for (const auto& r : u.localisers)
			MRPT_LOG_DEBUG_FMT(
				"frame %zu %s: kf %u, %d matches, %d inliers, gate median %.1f px (%d of %d overflow), sigma %.3f m, "
				"rms %.2f px, var factor %.2f, %s",
				u.frame, r.channel.c_str(), r.kf_id, r.matches, r.inliers, r.gate.median_axis_px, r.gate.overflow,
				r.gate.predicted, r.sigma_m, r.rms_px, r.var_factor, toString(r.status).c_str());
	u.ms_total = msSince(tAll);
	if (m_hook) m_hook(u, meas, calib);
	// A frame the fallback VO did not track is where it starts from when it
	// is next needed: its measurements are kept, not copied.
	if (m_voFallback && !m_voFallback->trackedLast)
		m_voFallback->standby = TVOTrack::TStandby{std::move(meas[m_voFallback->pipe]), calib, timestamp};
	return u;
}

const StereoLocaliser* LocalisationSystem::localiser(const std::string& label) const
{
	for (const auto& p : m_pipes)
		if (p.setup.channel.label == label) return p.localiser.get();
	return nullptr;
}

}  // namespace shadyloc::localisation
