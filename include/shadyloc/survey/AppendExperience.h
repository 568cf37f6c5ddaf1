/* ShadyLoc — a survey run added to a map as a new experience (`shadyloc
 * survey --append`), after Churchill and Newman, "Experience-based
 * navigation for long-term localisation" (IJRR 2013): a map holds several
 * runs of a route, each with its own keyframe chain and landmarks, and
 * localises against all of them.
 *
 * The new run is surveyed on its own (SurveyRun) and localised against the
 * map (LocaliseRun); its fixes at its own keyframes are candidate links
 * (keyframe b of the new run in keyframe a of the map). A candidate is kept
 * only where the loop it closes with another candidate nearby (the map's
 * chain between the two a's, the new run's between the two b's) agrees
 * within chi^2: one wrong fix closes no loop. With enough verified links
 * into one frame (the map's, or that of an experience kept in its own) the
 * run is anchored there: each of its keyframes is placed from the link
 * nearest it along its chain. Without, it keeps its own frame
 * ("linked nowhere": never chained to the others, found by the global
 * search alone). Pure: no images, tested alone.
 */
#pragma once

#include <shadyloc/geometry/PoseCovariance.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace shadyloc::survey
{
/** A fix of a frame of the new run against the map: the live left camera in
 * map keyframe `kf` (LocalisationSystem's used fix). */
struct TRunFix
{
	uint64_t frame = 0;	 //!< index of the frame in the new run (TMapKeyframe::frame)
	uint32_t kf = 0;  //!< map keyframe
	Eigen::Isometry3d T_kf_live = Eigen::Isometry3d::Identity();
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();
};

/** Frames first..last of a run (inclusive). */
struct TFrameRange
{
	uint64_t first = 0, last = 0;
};

struct TAppendOptions
{
	/** Two candidate links agree when the loop they close passes this
	 * chi^2 test (6 dof; 16.81 = 99 %) [-]. */
	double loop_chi2 = 16.81;
	/** ... and lie at most this far apart along the new run's chain [m]. */
	double loop_window_m = 15.0;
	/** Verified links needed to anchor the run in the map frame. */
	int min_links = 3;
};

/** What one candidate link became. */
struct TLinkReport
{
	map::TExperienceLink link;	//!< keyframe ids in the output map
	bool verified = false;
	int agreeing = 0;  //!< other candidates whose loop with this one passed
	/** Against the keyframes' ground truth, when both have it. */
	std::optional<double> err_m, err_deg;
};

struct TAppendReport
{
	std::string run;  //!< the new experience's name
	uint16_t run_index = 0;
	bool anchored = false;	//!< placed in a frame of the map through its links
	std::string frame_of;  //!< the run whose frame it is in (its own name when not anchored)
	size_t keyframes = 0;  //!< added
	size_t placed_from_other_segment = 0;  //!< anchored keyframes of a segment without a link (predicted)
	std::vector<TLinkReport> candidates;
	size_t verified() const;
};

/** Throws std::runtime_error naming both sides if `run` was made with
 * another camera, image size, channels (descriptor parameters) or map
 * options than `map`; `mapWhat` and `runWhat` name them. */
void checkAppendable(
	const CKeyframeMap& map, const CKeyframeMap& run, const std::string& mapWhat, const std::string& runWhat);

/** Appends the single-run map `run` to `map` as experience `name` (a name
 * the map does not hold yet), its keyframes after the map's, linked by the
 * verified `fixes` (fixes at frames that are no keyframe of `run` are not
 * used). With `keep`, only the keyframes of those frames are added, each
 * stretch a segment of its own (`localise --learn`: where the run went
 * blind, with the fixes around it as links). Checks as checkAppendable
 * first; throws if `keep` holds no keyframe; on any error `map` is unchanged. */
TAppendReport appendExperience(
	CKeyframeMap& map, const CKeyframeMap& run, const std::string& name, const std::vector<TRunFix>& fixes,
	const TAppendOptions& o = {}, const std::vector<TFrameRange>& keep = {});

}  // namespace shadyloc::survey
