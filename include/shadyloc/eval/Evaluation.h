/* ShadyLoc — evaluation of a localisation run: in-map frames, coverage,
 * true and false fixes against ground truth, blind episodes (McManus et al.
 * 2014, Section IV; definitions in docs/localisation.md). The evaluation's
 * area, not the localisation's: an application that localises links none
 * of it.
 *
 *  - in_map: a map keyframe lies within in_map_m and in_map_deg (optical
 *    axes) of the live frame's pose: the ground-truth poses of both when the
 *    live ground truth is given and the keyframes carry theirs, else the
 *    system's own estimate (frames with no known place count as in the map);
 *  - coverage = frames with a fix / in_map frames (all-frames coverage beside
 *    it); with ground truth, a fix is true when its pose relative to its
 *    keyframe is within true_max_m and true_max_deg of the truth
 *    T_kf_live = T_gt_kf^-1 T_gt_live (both runs' ground truth in one world
 *    frame, associated within assoc_dt_s; fewer than min_associated of the
 *    frames associated is an error), and true coverage counts true fixes only;
 *  - a blind episode is a maximal run of frames without a fix between two
 *    fixes, its length the distance travelled from the fix before it to the
 *    fix after it (ground truth where given, VO otherwise); the stretch
 *    before the first fix and the one after the last are reported apart.
 */
#pragma once

#include <shadyloc/eval/BlindEpisodes.h>
#include <shadyloc/eval/Proportion.h>
#include <shadyloc/io/Trajectory.h>
#include <shadyloc/localisation/LocalisationSystem.h>

#include <cstdint>
#include <string>
#include <vector>

namespace shadyloc::eval
{
/** A localised run: one update per live frame. */
using Updates = std::vector<localisation::TLocalisationUpdate>;

struct TEvalOptions
{
	double true_max_m = 0.5;  //!< a true fix is within this of the truth [m]
	double true_max_deg = 2.0;	//!< ... and this rotation [deg]
	double assoc_dt_s = 0.01;  //!< ground truth associated within this [s]
	double min_associated = 0.95;  //!< fraction of frames that must associate
	double in_map_m = 5.0;	//!< in_map radius [m]
	double in_map_deg = 30.0;  //!< in_map heading bound [deg]
	double blind_long_m = 100.0;  //!< P(an episode reaches this) is reported [m]
	int bootstrap_samples = 2000;  //!< resamples for the interval of that probability
	uint32_t bootstrap_seed = 1;
};

/** Truth of one fix. */
enum class FixTruth : int8_t
{
	None = -1,	//!< no fix, or nothing to check it against
	False = 0,
	True = 1
};

/** Per-frame evaluation. */
struct TFrameEval
{
	bool in_map = false;
	bool has_truth = false;	 //!< the live frame associated with ground truth
	double distance_m = 0;	//!< ground truth's travelled distance where given, else VO's [m]
	FixTruth used = FixTruth::None;	 //!< of the fix used
	double used_err_m = -1, used_err_deg = -1;	//!< its error (when checkable)
	std::vector<FixTruth> channel;	//!< per localiser (policy order): of its own accepted fix
	/** Per localiser (policy order), of its solve whether accepted or not
	 * (the solve log): error against the truth [m], [deg] (-1: no solve or
	 * no truth), and its normalised estimation error squared
	 * xi^T cov^-1 xi (6 dof; -1: none). */
	std::vector<double> solve_err_m, solve_err_deg, solve_nees;
};


struct TChannelSummary
{
	std::string channel;
	size_t accepted = 0;  //!< accepted fixes of this localiser
	size_t used = 0;  //!< ... of which the policy used
	size_t true_fixes = 0, false_fixes = 0, unverifiable = 0;  //!< with ground truth
};

struct TEvaluation
{
	std::vector<TFrameEval> frames;
	bool ground_truth = false;	//!< the live ground truth was given
	size_t associated = 0;	//!< frames associated with it
	size_t in_map_frames = 0, fixes = 0, fixes_in_map = 0;
	size_t true_fixes = 0, true_fixes_in_map = 0, false_fixes = 0, unverifiable = 0;
	double coverage_in_map = 0, coverage_all = 0;  //!< self-reported [0..1]
	double true_coverage_in_map = 0, true_coverage_all = 0;	 //!< ground truth [0..1]
	double false_fix_share = 0;	 //!< false / (true + false) fixes [0..1]
	std::vector<TChannelSummary> channels;
	std::vector<TBlindEpisode> episodes;
	size_t episodes_between = 0, episodes_long = 0;	 //!< Between episodes; of which >= blind_long_m
	double p_long = 0, p_long_lo = 0, p_long_hi = 0;  //!< P(episode >= blind_long_m), 95 % bootstrap interval
	double p_long_exact_lo = 0, p_long_exact_hi = 1;  //!< its exact 95 % (Clopper-Pearson) interval
	double blind_m = 0, total_m = 0, blind_m_per_km = 0;  //!< distance without a fix [m], total [m]
	double before_first_fix_m = -1;	 //!< distance before the first fix (-1: no fix) [m]
	int first_fix_frame = -1;
	size_t global_searches = 0;
	/** The oracle bound (Oracle.h), when the run was probed: in-map frames
	 * with a true single-shot fix per localiser (policy order) and with
	 * either; their shares of the in-map frames [0..1]. */
	bool oracle = false;
	std::vector<size_t> oracle_in_map;
	size_t oracle_any_in_map = 0;
	double oracle_any_coverage = 0;
};

/** P(a blind episode reaches o.blind_long_m) over episode lengths [m]: the
 * count, the exact 95 % (Clopper-Pearson) interval of the proportion (the
 * headline), and a 95 % percentile-bootstrap interval beside it
 * (o.bootstrap_samples resamples of the episodes, seeded by
 * o.bootstrap_seed: repeatable; it is [0, 0] when no episode reaches the
 * distance, which claims a certainty that a finite count cannot give).
 * evaluate() uses it for one run's episodes between fixes; the leave-one-out
 * evaluation for the episodes pooled over pairs (so the pooled interval comes
 * from the pooled counts). */
struct TBlindProbability
{
	size_t episodes = 0, reaching = 0;	//!< episodes; of which >= blind_long_m
	double p = 0;  //!< reaching / episodes [0..1]
	double exact_lo = 0, exact_hi = 1;	//!< exact 95 % interval (Clopper-Pearson) [0..1]
	double lo = 0, hi = 0;	//!< 95 % percentile-bootstrap interval [0..1]
};
TBlindProbability blindProbability(const std::vector<double>& lengths, const TEvalOptions& o = {});

/** Evaluates updates of one run against the map; `gt` (may be null) is the
 * live run's ground truth in the world frame of the map's keyframe ground
 * truth. Throws std::runtime_error when ground truth is given but fewer than
 * min_associated of the frames associate with it. */
TEvaluation evaluate(
	const Updates& updates, const CKeyframeMap& map, const io::Trajectory* gt,
	const TEvalOptions& o = {});

}  // namespace shadyloc::eval
