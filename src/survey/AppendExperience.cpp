/* ShadyLoc — a survey run added to a map as a new experience (see AppendExperience.h). */
#include <shadyloc/survey/AppendExperience.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <map>
#include <unordered_map>

namespace shadyloc::survey
{
using geometry::TPoseWithCov;

size_t TAppendReport::verified() const
{
	return static_cast<size_t>(
		std::count_if(candidates.begin(), candidates.end(), [](const TLinkReport& l) { return l.verified; }));
}

namespace
{
std::string channelList(const CKeyframeMap& m)
{
	std::string s;
	for (const auto& c : m.channels()) s += (s.empty() ? "" : ", ") + c.asString();
	return s;
}

/** A candidate link with run-local b. */
struct TCandidate
{
	uint32_t a = 0, b = 0;
	TPoseWithCov T_a_b;
};

/** Whether the loop of candidates i and j closes: the map's T_ai_aj against
 * T_ai_bi T_bi_bj T_bj_aj through the run's chain. */
bool loopCloses(
	const CKeyframeMap& map, const CKeyframeMap& run, const TCandidate& i, const TCandidate& j, double chi2)
{
	const auto viaMap = map.measuredRelativePose(i.a, j.a);
	if (!viaMap || !run.sameSegment(i.b, j.b)) return false;
	const auto rb = run.relativePose(i.b, j.b);
	const TPoseWithCov viaRun =
		geometry::compose(geometry::compose(i.T_a_b, {rb.T_a_b, rb.cov}), geometry::inverse(j.T_a_b));
	const double d2 = geometry::mahalanobis2(geometry::localLeft(viaRun.T, viaMap->T_a_b), viaRun.cov + viaMap->cov);
	return d2 <= chi2;
}

/** The verified candidate nearest run keyframe b: in its segment by chain
 * distance, else (a segment with none) in any segment by keyframe order. */
std::pair<const TCandidate*, bool> nearestLink(
	const CKeyframeMap& run, const std::vector<const TCandidate*>& verified, uint32_t b)
{
	const TCandidate* best = nullptr;
	double bestD = std::numeric_limits<double>::infinity();
	for (const auto* c : verified)
		if (run.sameSegment(c->b, b))
		{
			const double d = std::abs(run.chainDistance(c->b) - run.chainDistance(b));
			if (d < bestD) bestD = d, best = c;
		}
	if (best) return {best, true};
	for (const auto* c : verified)
	{
		const double d = std::abs(double(c->b) - double(b));
		if (d < bestD) bestD = d, best = c;
	}
	return {best, false};
}
}  // namespace

void checkAppendable(
	const CKeyframeMap& map, const CKeyframeMap& run, const std::string& mapWhat, const std::string& runWhat)
{
	const auto refuse = [&](const std::string& what, const std::string& m, const std::string& r) {
		throw std::runtime_error(
			"cannot append " + runWhat + " to " + mapWhat + ": other " + what + " (map: " + m + "; new run: " + r + ")");
	};
	if (map.keyframeCount() == 0) throw std::runtime_error(mapWhat + " has no keyframes: survey it first");
	if (run.keyframeCount() == 0) throw std::runtime_error(runWhat + " has no keyframes");
	if (run.runs().size() != 1)
		throw std::runtime_error(runWhat + " holds " + std::to_string(run.runs().size()) + " runs: one run is appended at a time");
	const auto& cm = map.calibration();
	const auto& cr = run.calibration();
	const bool sameCamera = map.imageWidth() == run.imageWidth() && map.imageHeight() == run.imageHeight() &&
							std::abs(cm.fx - cr.fx) <= 1e-6 * cm.fx && std::abs(cm.fy - cr.fy) <= 1e-6 * cm.fy &&
							std::abs(cm.cx - cr.cx) <= 1e-6 * cm.fx && std::abs(cm.cy - cr.cy) <= 1e-6 * cm.fy &&
							std::abs(cm.cxR - cr.cxR) <= 1e-6 * cm.fx && std::abs(cm.baseline - cr.baseline) <= 1e-6 * cm.baseline;
	if (!sameCamera)
		refuse(
			"camera", std::to_string(map.imageWidth()) + "x" + std::to_string(map.imageHeight()) + " " + cm.asString(),
			std::to_string(run.imageWidth()) + "x" + std::to_string(run.imageHeight()) + " " + cr.asString());
	bool sameChannels = map.channels().size() == run.channels().size();
	for (size_t c = 0; sameChannels && c < map.channels().size(); c++)
		sameChannels = map.channels()[c] == run.channels()[c];
	if (!sameChannels) refuse("channels or descriptor parameters", channelList(map), channelList(run));
	if (!(map.options == run.options))
	{
		std::ostringstream m, r;
		map.options.dumpToTextStream(m);
		run.options.dumpToTextStream(r);
		refuse("map options ([map])", m.str(), r.str());
	}
}

TAppendReport appendExperience(
	CKeyframeMap& map, const CKeyframeMap& run, const std::string& name, const std::vector<TRunFix>& fixes,
	const TAppendOptions& o, const std::vector<TFrameRange>& keep)
{
	const auto kept = [&](uint64_t frame) {
		return keep.empty() ||
			   std::any_of(keep.begin(), keep.end(), [&](const TFrameRange& r) { return frame >= r.first && frame <= r.last; });
	};
	if (std::none_of(run.keyframes().begin(), run.keyframes().end(), [&](const auto& k) { return kept(k.frame); }))
		throw std::runtime_error("run '" + name + "': no keyframe in the frames to add");
	checkAppendable(map, run, "the map", "run '" + name + "'");
	for (const auto& r : map.runs())
		if (r == name) throw std::runtime_error("the map already holds a run named '" + name + "': name the new one otherwise");

	// ---- candidates: fixes at the run's keyframes
	std::unordered_map<uint64_t, uint32_t> kfAtFrame;
	for (const auto& k : run.keyframes())
		if (kept(k.frame)) kfAtFrame.emplace(k.frame, k.id);
	std::vector<TCandidate> cands;
	for (const auto& f : fixes)
	{
		const auto it = kfAtFrame.find(f.frame);
		if (it == kfAtFrame.end()) continue;
		map.keyframe(f.kf);	 // throws naming an unknown keyframe
		cands.push_back({f.kf, it->second, {f.T_kf_live, f.cov}});
	}

	// ---- verification: each candidate's loops with its neighbours
	std::vector<int> agreeing(cands.size(), 0);
	for (size_t i = 0; i < cands.size(); i++)
		for (size_t j = i + 1; j < cands.size(); j++)
		{
			if (!run.sameSegment(cands[i].b, cands[j].b) ||
				std::abs(run.chainDistance(cands[i].b) - run.chainDistance(cands[j].b)) > o.loop_window_m)
				continue;
			if (loopCloses(map, run, cands[i], cands[j], o.loop_chi2)) agreeing[i]++, agreeing[j]++;
		}
	// The frame the run is placed in: that of most verified links (a map
	// may hold experiences in frames of their own); only its links place it.
	std::map<uint32_t, int> linksInFrame;
	for (size_t i = 0; i < cands.size(); i++)
		if (agreeing[i] > 0) linksInFrame[map.frameOf(cands[i].a)]++;
	uint32_t frame = 0;
	int most = 0;
	for (const auto& [f, n] : linksInFrame)
		if (n > most) most = n, frame = f;
	std::vector<const TCandidate*> verified;
	for (size_t i = 0; i < cands.size(); i++)
		if (agreeing[i] > 0 && map.frameOf(cands[i].a) == frame) verified.push_back(&cands[i]);

	// ---- the new run's keyframes, after the map's
	TAppendReport rep;
	rep.run = name;
	rep.anchored = static_cast<int>(verified.size()) >= o.min_links;
	rep.frame_of = rep.anchored ? map.runs()[frame] : name;
	CKeyframeMap out = map;	 // the map stays as it was if anything throws
	rep.run_index = out.addRun(name, rep.anchored ? static_cast<int>(frame) : CKeyframeMap::kOwnFrame);
	// A segment per stretch of consecutive kept keyframes of one run segment.
	std::unordered_map<uint32_t, uint32_t> idOf;  // run keyframe -> output map keyframe
	uint32_t segment = map.keyframes().back().segment;
	const map::TMapKeyframe* prev = nullptr;
	for (const auto& k0 : run.keyframes())
	{
		if (!kept(k0.frame)) continue;
		if (!prev || prev->segment != k0.segment || prev->id + 1 != k0.id) segment++;
		prev = &k0;
		map::TMapKeyframe k = k0;
		k.run = rep.run_index;
		k.segment = segment;
		if (rep.anchored)
		{
			const auto [l, sameSegment] = nearestLink(run, verified, k0.id);
			// T_map_b = T_map_a T_a_bl T_bl_b, T_bl_b along the run (its own
			// frame's poses across a break of the run, which are predicted).
			const Eigen::Isometry3d T_bl_b = sameSegment ? run.relativePose(l->b, k0.id).T_a_b
														 : run.keyframe(l->b).T_map_kf.inverse() * k0.T_map_kf;
			k.T_map_kf = map.keyframe(l->a).T_map_kf * l->T_a_b.T * T_bl_b;
			k.predicted = k0.predicted || !sameSegment || map.keyframe(l->a).predicted;
			rep.placed_from_other_segment += !sameSegment;
		}
		idOf[k0.id] = static_cast<uint32_t>(out.keyframeCount());
		out.appendKeyframe(std::move(k));
	}
	rep.keyframes = idOf.size();

	// ---- links: every verified candidate, reported with its truth
	for (size_t i = 0; i < cands.size(); i++)
	{
		TLinkReport lr;
		lr.link.a = cands[i].a;
		lr.link.b = idOf.at(cands[i].b);
		lr.link.T_a_b = cands[i].T_a_b.T;
		lr.link.cov = cands[i].T_a_b.cov;
		lr.agreeing = agreeing[i];
		lr.verified = agreeing[i] > 0;
		const auto& ga = out.keyframe(lr.link.a).T_gt_kf;
		const auto& gb = out.keyframe(lr.link.b).T_gt_kf;
		if (ga && gb)
		{
			const Eigen::Isometry3d E = (ga->inverse() * *gb).inverse() * lr.link.T_a_b;
			lr.err_m = E.translation().norm();
			lr.err_deg = Eigen::AngleAxisd(E.linear()).angle() * 180.0 / M_PI;
		}
		if (lr.verified) out.addLink(lr.link);
		rep.candidates.push_back(lr);
	}
	map = std::move(out);
	return rep;
}

}  // namespace shadyloc::survey
