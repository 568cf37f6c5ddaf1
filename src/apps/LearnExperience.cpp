/* ShadyLoc — `shadyloc localise --learn` (see LearnExperience.h). */
#include "LearnExperience.h"

#include <shadyloc/eval/BlindEpisodes.h>
#include <shadyloc/survey/SurveyRun.h>

#include <iomanip>

namespace shadyloc::apps
{
std::vector<survey::TFrameRange> framesToLearn(
	const std::vector<localisation::TLocalisationUpdate>& ups, const TLearnOptions& o)
{
	std::vector<bool> fix;
	std::vector<double> dist;
	for (const auto& u : ups)
	{
		fix.push_back(u.localised());
		dist.push_back(u.distance_m);
	}
	std::vector<survey::TFrameRange> out;
	for (const auto& e : eval::blindEpisodes(fix, dist))
	{
		if (e.length_m <= o.blind_m) continue;
		size_t a = e.first, b = e.last;
		while (a > 0 && dist[e.first] - dist[a - 1] <= o.margin_m) a--;
		while (b + 1 < ups.size() && dist[b + 1] - dist[e.last] <= o.margin_m) b++;
		const uint64_t first = ups[a].frame, last = ups[b].frame;
		if (!out.empty() && first <= out.back().last + 1)
			out.back().last = std::max(out.back().last, last);	// widened stretches that meet are one
		else
			out.push_back({first, last});
	}
	return out;
}

CKeyframeMap::Ptr learnExperience(
	const mrpt::config::CConfigFileBase& cfg, const std::string& cfgWhat, const CKeyframeMap& map,
	const std::string& livePath, const std::optional<io::Trajectory>& gt, const std::string& sensorLabel,
	const std::vector<localisation::TLocalisationUpdate>& ups, const TLearnOptions& o, std::ostream& log)
{
	const auto frames = framesToLearn(ups, o);
	if (frames.empty())
	{
		log << "learn: no blind stretch longer than " << o.blind_m << " m: nothing to learn, the map is unchanged\n";
		return nullptr;
	}
	survey::TSurveyRunOptions so;
	so.configName = cfgWhat;
	so.sensorLabel = sensorLabel;
	so.channels.clear();
	for (const auto& c : map.channels()) so.channels.push_back(c.label);
	if (gt)
	{
		so.gt = gt;
		so.gtName = "the live run's ground truth";
	}
	survey::SurveyRun surveyRun(livePath, cfg, so);
	surveyRun.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	const CKeyframeMap::Ptr runMap = surveyRun.run();
	std::vector<survey::TRunFix> fixes;
	for (const auto& u : ups)
		if (u.localised()) fixes.push_back({u.frame, u.kf_id, u.T_kf_live, u.cov});
	auto learnt = CKeyframeMap::Create(map);
	const auto rep = survey::appendExperience(*learnt, *runMap, surveyRun.runName(), fixes, {}, frames);
	log << "learn: " << frames.size() << " blind stretch(es) longer than " << o.blind_m << " m -> experience '"
		<< rep.run << "': " << rep.keyframes << " keyframes, " << rep.verified() << " of " << rep.candidates.size()
		<< " candidate links verified, "
		<< (rep.anchored ? "anchored in the frame of '" + rep.frame_of + "'" : std::string("linked nowhere (its own frame)")) << "\n";
	return learnt;
}

}  // namespace shadyloc::apps
