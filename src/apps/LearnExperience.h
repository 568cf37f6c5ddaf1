/* ShadyLoc — `shadyloc localise --learn`: where a live run went blind, its
 * keyframes there become a new experience of the map (survey/
 * AppendExperience.h), linked by the run's fixes around each stretch; a run
 * that localised everywhere adds nothing (Churchill and Newman, IJRR 2013). */
#pragma once

#include <shadyloc/io/Trajectory.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/survey/AppendExperience.h>

#include <mrpt/config/CConfigFileBase.h>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace shadyloc::apps
{
struct TLearnOptions
{
	double blind_m = 10.0;	//!< a blind episode longer than this is learnt [m]
	double margin_m = 5.0;	//!< ... with this much of the run on either side, where its fixes link it [m]
};

/** The frames of a run to add to its map: each blind episode longer than
 * blind_m (by VO's distance), widened by margin_m of travel on each side. */
std::vector<survey::TFrameRange> framesToLearn(
	const std::vector<localisation::TLocalisationUpdate>& ups, const TLearnOptions& o);

/** Surveys the live rawlog (the map's channels, the chain on the first) and
 * appends its frames to learn to a copy of `map` as experience `name`;
 * nullptr when there is nothing to learn. Says what it did on `log`. */
CKeyframeMap::Ptr learnExperience(
	const mrpt::config::CConfigFileBase& cfg, const std::string& cfgWhat, const CKeyframeMap& map,
	const std::string& livePath, const std::optional<io::Trajectory>& gt, const std::string& sensorLabel,
	const std::vector<localisation::TLocalisationUpdate>& ups, const TLearnOptions& o, std::ostream& log);

}  // namespace shadyloc::apps
