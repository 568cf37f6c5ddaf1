/* ShadyLoc — the system's track and its switching policy, apart from the
 * images (tested alone: tests/unit/test_localisation_stages.cpp).
 *
 * The track is the last accepted fix (or verified place) propagated by VO:
 *  - predict(): composes it with VO's step and adds drift that grows in
 *    proportion to the distance dead-reckoned since the last fix
 *    (sigma = k * d, whatever the frame rate: driftCovariance);
 *  - the track is a confirmed place after a fix, until a global search
 *    adopts a new place or its uncertainty outgrows confirmed_max_sigma_m;
 *    while confirmed, a consistent solve of any localiser is a fix at once
 *    (FixAcceptance.h);
 *  - the policy (McManus et al. 2014, Section III-B): the first localiser
 *    in policy order with an accepted fix is used; none: dead reckoning;
 *  - an unconfirmed but consistent solve may narrow the next frame's
 *    search, never the track a solve is validated against;
 *  - relocalisation: after relocalise_after_frames without a fix (or when
 *    every localiser is lost) the place is searched for around dead
 *    reckoning, within relocalise_window_m along the map's chain or in
 *    the map frame (the next segment after a VO break of the survey), on the
 *    same frame; after global_search_after_frames, in the whole map.
 */
#pragma once

#include <shadyloc/localisation/FixAcceptance.h>


#include <functional>
#include <vector>

namespace shadyloc::localisation
{
struct TTrackOptions
{
	/** Drift of dead reckoning: standard deviation per metre since the last
	 * fix [m/m], [deg/m]. */
	double drift_m_per_m = 0.02;
	double drift_deg_per_m = 0.2;
	/** The track stays a confirmed place while its largest translational
	 * standard deviation is below this [m]. */
	double confirmed_max_sigma_m = 0.5;
	int relocalise_after_frames = 1;  //!< frames without a fix before the windowed search (1: every lost frame) [frames]
	double relocalise_window_m = 20.0;	//!< ... along the chain on both sides of dead reckoning, and as near in the map frame (any segment) [m]
	double relocalise_max_angle_deg = 45.0;	 //!< ... a keyframe of another segment there facing within this of dead reckoning [deg]
	/** The relocalisation's first pass matches each candidate where dead
	 * reckoning projects its landmarks, through their warps (then, if that
	 * fails, as if at the keyframe): a live run to the side of the survey. */
	bool relocalise_at_dead_reckoning = true;
	int global_search_after_frames = 30;  //!< frames without a fix before the whole map is searched [frames]
	/** A whole-map search looks at most this many keyframes a frame, the
	 * next slice of the map each time (MapSweep; 0: the whole map). */
	int global_keyframes_per_frame = 128;
	/** Added to a global-search place's covariance (one frame's solve) [m], [deg]. */
	double global_sigma_m = 0.1;
	double global_sigma_deg = 1.0;
	/** An unconfirmed, consistent solve narrows the next frame's search. */
	bool seed_with_unconfirmed = true;
	/** While the track is confirmed, a fix is the solve fused with the
	 * prediction (fuseWithPrediction), not the solve alone. */
	bool fuse_prediction = true;
	/** When the localisers' fixes of one frame disagree, the most certain
	 * is used, not the first in policy order (chooseFix). */
	bool cross_check_fixes = true;
	/** Which fixes that disagree with a more certain fix of the same frame
	 * are no fix at all (status contradicted; contradictedFixes), their
	 * localisers forgetting them (no reference either). */
	enum class Contradicted
	{
		Kept,  //!< none: cross_check_fixes only chooses among them
		Joint,	//!< the joint localiser's: the union pulled by one channel's wrong matches
		All	 //!< any localiser's
	};
	Contradicted reject_contradicted = Contradicted::Kept;
	/** A verified place that is no fix replaces a confirmed track only when
	 * it is the more certain of the two (largest translational sigma, the
	 * place's with global_sigma_m added), or when a second place agrees with
	 * it through VO; else the track is kept. One frame after a fix, a lone
	 * place that contradicts the track was more often the wrong one; places
	 * that keep agreeing with each other against it are evidence that the
	 * track is wrong (docs/localisation.md). */
	bool confirmed_track_outranks_places = true;
};

/** What a verified place of the relocalisation did to the track. */
enum class PlaceOutcome
{
	Fix,  //!< a fix: the track restarts from it, confirmed
	Hypothesis,	 //!< it starts or continues an unconfirmed hypothesis
	Outranked  //!< a more certain confirmed track was kept; the place is its rival
};

/** Whether a verified place agrees with a prediction for its frame
 * (placeAgrees with the place, its link and chi^2 bound in). */
using PlaceTest = std::function<bool(const TKeyframePose& pred)>;

/** Covariance added by a dead-reckoned step of `step` metres after `before`
 * metres without a fix: the variance of drift k * d grows from
 * (k before)^2 to (k (before + step))^2 (k: drift per metre) [m^2, rad^2]. */
geometry::Matrix6d driftCovariance(double before, double step, double k_m_per_m, double k_deg_per_m);

/** Whether a verified place agrees with the track's prediction `pred` for
 * its frame (chi^2 on the sum of covariances, `link` between keyframes). */
bool placeAgrees(const TKeyframePose& place, const TKeyframePose& pred, const KeyframeLink& link, double chi2);

/** Which of one frame's accepted fixes (in policy order, each with its
 * largest translational standard deviation [m]) the frame uses: the first,
 * unless another disagrees with it (chi^2 on the sum of their covariances
 * above `chi2`, through `link`); then the most certain. Two channels that
 * contradict each other cannot both be right, and the policy order says
 * nothing about which is: on the 301 m set the more certain was the nearer
 * the truth in 9 of 10 such frames (docs/localisation.md). */
size_t chooseFix(
	const std::vector<TKeyframePose>& fixes, const std::vector<double>& sigma_m, const KeyframeLink& link, double chi2);

/** Which of one frame's accepted fixes are contradicted: taken from the
 * most certain (smallest sigma_m) on, a fix that disagrees (chi^2 through
 * `link` above `chi2`) with a more certain one that is kept is contradicted.
 * The fixes kept agree pairwise. */
std::vector<bool> contradictedFixes(
	const std::vector<TKeyframePose>& fixes, const std::vector<double>& sigma_m, const KeyframeLink& link, double chi2);

/** Where the place is searched for on a frame without a fix. */
enum class SearchScope
{
	None,
	Window,	 //!< around dead reckoning
	Whole  //!< the whole map (or the start keyframes)
};

/** The keyframes of successive whole-map searches: the map in slices of at
 * most `budget` consecutive keyframes, round robin, so that a lost run's
 * search costs a bounded time a frame however many experiences the map
 * holds; the place is found within keyframes/budget frames (budget 0 or at
 * least the map's size: the whole map every time). */
class MapSweep
{
   public:
	MapSweep(uint32_t keyframes, int budget) : m_keyframes(keyframes), m_budget(budget) {}
	/** The next slice, in ascending keyframe order (empty for an empty map). */
	std::vector<uint32_t> next();
	/** The next slice starts at keyframe 0 again (a new run). */
	void restart() { m_next = 0; }

   private:
	uint32_t m_keyframes;
	int m_budget;
	uint32_t m_next = 0;
};

class Track
{
   public:
	explicit Track(const TTrackOptions& o = {}) : m_opts(o) {}

	/** The track propagated by VO's step (invalid when no place is known). */
	TKeyframePose predict(const TMotion& motion);
	/** Where to search this frame when not around the prediction: the last
	 * frame's unconfirmed solve propagated by the same step, when tighter
	 * than the prediction (invalid otherwise). */
	const TKeyframePose& searchSeed() const { return m_seedPred; }
	/** The prediction is of a confirmed place (see the file comment). */
	bool confirmed() const;

	/** A fix was used: the track restarts from it, confirmed. */
	void fix(const TKeyframePose& fix);
	/** No fix: dead reckoning; `seeds` are this frame's unconfirmed solves. */
	void noFix(const std::vector<TKeyframePose>& seeds);
	/** Whether (and where) to search for the place now. `allLost`: every
	 * localiser said its gates outgrew the ceiling. */
	SearchScope searchNeeded(bool allLost) const;
	/** A verified place becomes the track: a new, unconfirmed hypothesis,
	 * tested against with global_sigma added. With `seedsSearch` (its
	 * localiser's place_seeds_search) it also narrows the next frame's
	 * search with its own covariance; it never validates. */
	void adoptPlace(const TKeyframePose& place, bool seedsSearch = false);
	/** A verified place of the relocalisation. `agreesWith`: the place
	 * against a prediction for its frame (placeAgrees); `certain`: within the
	 * fix bounds. A fix when it agrees with a confirmed track, or is the K-th
	 * agreeing place of the unconfirmed hypothesis (two verified places that
	 * agree through VO confirm as K consistent frames do; replacing the
	 * hypothesis instead restarted it on every search). Otherwise it
	 * continues the hypothesis it agrees with, or starts a new one, unless a
	 * confirmed track is the more certain (confirmed_track_outranks_places):
	 * then the place is the track's rival, and the next place that agrees
	 * with the rival overturns the track. `seedsSearch`: see adoptPlace. */
	PlaceOutcome placeFound(
		const TKeyframePose& place, const PlaceTest& agreesWith, bool certain, int K, bool seedsSearch = false);
	/** Verified places that agree in the current unconfirmed hypothesis
	 * (0: none, or the track is a fix's). */
	int hypothesisPlaces() const { return m_places; }

	const TKeyframePose& estimate() const { return m_est; }
	int framesSinceFix() const { return m_framesSinceFix; }
	double distanceSinceFix() const { return m_distSinceFix; }
	void reset() { *this = Track(m_opts); }

   private:
	/** A place's covariance as the track would hold it (global_sigma added). */
	geometry::Matrix6d withPlaceSigma(const geometry::Matrix6d& cov) const;

	TTrackOptions m_opts;
	TKeyframePose m_est;  //!< the track after the last frame
	TKeyframePose m_pred, m_seedPred;  //!< this frame's prediction and seed
	TKeyframePose m_seed;  //!< an unconfirmed solve of the last frame
	TKeyframePose m_rival;	//!< a place outranked by the confirmed track, propagated by VO
	double m_rivalDist = 0;	 //!< metres dead-reckoned since the rival was found
	bool m_confirmed = false;
	int m_places = 0;
	int m_framesSinceFix = 0;
	double m_distSinceFix = 0;
};

}  // namespace shadyloc::localisation
