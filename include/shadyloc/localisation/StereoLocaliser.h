/* ShadyLoc — one localiser: a live stereo frame of one channel against the
 * dual-channel keyframe map (McManus et al. 2014, Sections II-B and III-B).
 * The same class serves every channel; the combined system makes one per
 * channel from config (monochrome, illumination-invariant).
 *
 * Per frame (localise()):
 *   1. keyframe choice: from the predicted pose (the system's track, or a
 *      tighter search seed), the keyframe nearest a point
 *      look-ahead metres in front of the camera along the chain, heading
 *      included (roads are driven both ways); the prediction is re-expressed
 *      in that keyframe with the inter-keyframe covariance;
 *   2. active search: every landmark's predicted stereo measurement
 *      (uL, v, uR) with the covariance of the landmark, the pixel noise and
 *      the prediction (vo::KeyframeMatcher::predict), a chi-square gate with
 *      a floor; when the gates grow past the ceiling the localiser declares
 *      itself lost (it never clips a gate); BRIEF inside, patch refinement;
 *      the same for the chosen keyframe's neighbours along the chain (the
 *      local map), their correspondences moved into the chosen keyframe;
 *   3. one RANSAC and one robust solve for T_kf_live with covariance,
 *      WITHOUT the motion prior (a RANSAC that favours the prediction would
 *      agree with it by construction, and the failure test would test
 *      nothing);
 *   4. acceptance (FixAcceptance): too few inliers, too uncertain, the fix
 *      against the track's prediction, the frame-to-frame motion against
 *      VO's; K consistent frames only for a new place.
 * Starting and recovering: globalSearch() votes with BRIEF over every
 * keyframe and verifies the best candidates geometrically (RANSAC + solve);
 * it never returns a place without a verified pose, nor an ambiguous one.
 * docs/localisation.md.
 */
#pragma once

#include <shadyloc/features/DescriptorGroups.h>
#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/localisation/FixAcceptance.h>
#include <shadyloc/geometry/PoseCovariance.h>
#include <shadyloc/geometry/PoseSolver.h>
#include <shadyloc/geometry/StereoCamera.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/vo/KeyframeMatcher.h>
#include <shadyloc/vo/RelativePoseEstimator.h>

#include <mrpt/config/CConfigFileBase.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <limits>
#include <optional>
#include <ostream>
#include <string>

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::localisation
{
/** How the localiser searches for each landmark's match (must-show 4). */
enum class SearchMode
{
	Gate,  //!< the chi-square gate of the predicted measurement (active search, the default)
	Window,	 //!< a fixed circle of window_px around the predicted projection
	Global	//!< every measurement of the frame (global BRIEF matching to the keyframe)
};
std::string toString(SearchMode m);

/** Options of one localiser ([localiser], then [localiser.<channel>]
 * overrides; config/localise_sim.ini). */
struct TLocaliserOptions
{
	// ---- keyframe choice
	double kf_back_m = 6.0;	 //!< keyframes considered behind the predicted keyframe along the chain [m]
	double kf_ahead_m = 12.0;  //!< ... and ahead of it [m]
	/** The keyframe nearest the point this far in front of the predicted
	 * camera is taken [m]. 0 = the nearest keyframe: on the simulator a live
	 * frame re-finds about half as many landmarks of a keyframe 2.5 m ahead
	 * as of one within 0.2 m (docs/localisation.md), so looking ahead costs. */
	double kf_lookahead_m = 0.0;
	double kf_max_distance_m = 6.0;	 //!< farther keyframes are not used [m]
	/** The local map: the landmarks of the keyframes within this distance
	 * along the chain of the chosen one are searched too, in one RANSAC and
	 * one solve (0 = the chosen keyframe only). A live frame half-way
	 * between two keyframes re-finds part of each [m]. */
	double kf_window_m = 1.6;
	int kf_window_max = 2;	//!< at most this many keyframes, nearest the prediction first
	double kf_max_angle_deg = 30.0;	 //!< optical axes farther apart are not used [deg]
	double kf_angle_weight_m_per_deg = 0.1;	 //!< ranking: metres a degree of heading is worth [m/deg]
	/** In a map of several experiences, a keyframe of the prediction's
	 * experience (the one that localised last) while it has one in range;
	 * another only where it has none. A lost frame's relocalisation searches
	 * every experience, so a failing one is left there. Off: the nearest of
	 * any experience (it alternated between two every frame and lost
	 * coverage through the links). */
	bool kf_stay_in_experience = true;
	/** ... and up to this many experiences searched per frame: the
	 * prediction's, then the others with a keyframe in range, nearest first;
	 * the solve with the most inliers is the frame's (the cost per frame is
	 * bounded by this, however many experiences the map holds). */
	int kf_experiences_per_frame = 1;
	/** Covariance added when the prediction crosses from one chain segment to
	 * another (their link is not measured): standard deviations [m], [deg]. */
	double cross_segment_sigma_m = 2.0;
	double cross_segment_sigma_deg = 5.0;

	// ---- search
	SearchMode search = SearchMode::Gate;
	double gate_chi2 = 11.34;  //!< gate on (uL, v, uR): 99 % of chi^2 with 3 degrees of freedom
	double gate_min_px = 3.0;  //!< every gate axis at least this long [px]
	/** Gate ceiling: a landmark whose gate axis is longer is not searched;
	 * when more than max_overflow_fraction of the visible landmarks overflow,
	 * the localiser is lost (status lost) [px]. */
	double gate_max_px = 60.0;
	/** The ceiling above bounds the prediction's part of the gate (pose
	 * covariance, pixel noise); with the landmark's own covariance the gate
	 * may reach this. A map landmark triangulated over the rig's baseline b
	 * and seen from B metres aside is uncertain along the epipolar line by
	 * about B / b times its disparity noise at any depth: the prediction is
	 * not lost, the landmark is uncertain (docs/localisation.md, "The other
	 * lane"). 0 = gate_max_px bounds the whole gate [px]. */
	double gate_landmark_max_px = 150.0;
	double max_overflow_fraction = 0.5;	 //!< see gate_max_px
	/** A frame that finds too few matches or inliers in its gates searches
	 * once more with the prediction's covariance scaled by this squared (its
	 * part of every gate by this); 1 = no second search [-]. */
	double retry_gate_scale = 2.0;
	double window_px = 40.0;  //!< Window: circle radius [px]
	int max_hamming = 80;  //!< largest BRIEF distance of a match [bits of 256]
	double match_ratio = 0.9;  //!< best < ratio * second best distance in the region
	double refine_min_zncc = 0.6;  //!< the refined patch must correlate this well
	int refine_radius_px = 2;  //!< refinement climbs at most this far from the BRIEF match [px]
	int refine_iterations = 5;	//!< Gauss-Newton steps of the sub-pixel refinement
	/** Match each landmark that has a surface normal through the warp its
	 * plane induces at the predicted pose (features/PatchWarp.h): BRIEF tests
	 * and refinement patch follow the viewpoint (docs/localisation.md,
	 * "Patches that follow the viewpoint"). */
	bool warp_patches = true;
	/** After a solve, search the local map's unmatched landmarks by
	 * projection with their patches and solve again with them
	 * (docs/localisation.md, "Search by projection with patches"). */
	bool patch_search = true;
	/** ... only where the descriptor solve keeps fewer inliers than this (0:
	 * after every solve): a solve that many inliers hold gains little
	 * from more (docs/localisation.md, "Where the patch pass runs"). */
	int patch_search_max_inliers = 0;
	int patch_search_radius_px = 2;	 //!< ... the patch climbs at most this far from the projection [px]
	double patch_min_zncc = 0.8;  //!< ... and must correlate this well there (no descriptor vouches for it)
	/** ... and when the descriptors find too few matches or inliers while
	 * the system's track is confirmed, search by patches at the prediction
	 * itself. */
	bool patch_search_from_prediction = true;
	/** ... or at a prediction whose position is this certain: a place the
	 * global search has just verified (its solve, plus global_sigma_m of
	 * the track options, 0.1 m) [m]. */
	double patch_prediction_max_sigma_m = 0.15;
	/** ... and the solve after it must keep this many of the descriptor
	 * matches as inliers: patches found at the prediction agree with it
	 * whether it is right or not. */
	int patch_prediction_min_descriptor_inliers = 6;
	/** ... where the warp distorts pixel offsets by more than this share [-]. */
	double warp_min_distortion = 0.1;

	// ---- solve
	double ransac_threshold_px = 3.0;  //!< inlier bound on |(duL, dv, duR)| [px]
	int ransac_iterations = 300;  //!< RANSAC upper bound
	double sigma_px = 0.5;	//!< measurement noise of the solve [px]
	double sigma_disparity_px = 0;	//!< the disparity's extra noise in the solve [px]
	double huber_k = 1.0;  //!< Huber threshold [sigmas]
	bool two_view_ba = true;  //!< two-view bundle adjustment (else fixed landmarks)
	int min_matches = 15;  //!< fewer matches after refinement: few_matches
	int min_inliers = 20;  //!< fewer inliers: few_inliers
	/** The solver's covariance is scaled by this before the tests (it is
	 * optimistic: correlated errors, model error) [-]. */
	double cov_scale = 1.5;
	/** Resamples of the inliers for the bootstrap covariance (0 = off): the
	 * fix's covariance is the larger of the scaled solver's and the
	 * bootstrap's in every direction; the bootstrap's is an empirical spread
	 * and is not scaled again (fixCovariance; docs/localisation.md) [-]. */
	int bootstrap_samples = 30;
	/** Each resample's steps re-linearise every correspondence (Gauss-Newton);
	 * off: the Jacobians and covariances are those at the solve, the
	 * residuals and Huber weights re-evaluated at every step (the chord
	 * method, geometry::solveStereoPoseCountedChord: the same fixed point to
	 * first order, for a fraction of the arithmetic). config/localise_sim.ini
	 * ships it off, judged on four data sets and the injected faults
	 * (docs/localisation.md, "Speed"). */
	bool bootstrap_relinearise = true;

	/** A fix whose standard deviation (largest axis of the scaled covariance)
	 * exceeds these is not accepted (status uncertain; 0 = no cap): 3.6 sigma
	 * of the 0.5 m / 2 deg a fix is judged by; the NEES tail makes 3 sigma
	 * too loose (docs/localisation.md, the trade-off) [m], [deg]. */
	double max_sigma_m = 0.14;
	double max_sigma_deg = 0.56;
	/** An uncertain solve is a failure (K consistent frames needed again);
	 * off: it is only not a fix, and when it passes the consistency tests it
	 * neither counts towards K nor resets it. */
	bool uncertain_breaks_chain = false;

	// ---- failure test
	/** Fix against prediction: Mahalanobis distance^2 bound, chi^2 with 6 dof
	 * (16.81 = 99 %) [-]. */
	double prediction_chi2 = 16.81;
	/** A solve whose translation sigma is at least this (0 = off) must pass
	 * the prediction test at uncertain_prediction_chi2 instead: the near
	 * misses the 99 % gate lets through are uncertain solves 3-4 sigma from
	 * a good prediction [m]. */
	double uncertain_sigma_m = 0.09;
	double uncertain_prediction_chi2 = 10.0;  //!< [-]
	/** Frame-to-frame motion of two consecutive solves against VO's [-]. */
	double motion_chi2 = 22.46;
	int consistent_frames = 3;	//!< K: consecutive consistent frames before fixes are accepted again

	// ---- global search
	int global_vote_hamming = 50;  //!< a landmark votes for its keyframe when a live descriptor is this close [bits]
	int global_candidates = 5;	//!< keyframes verified geometrically, most votes first
	/** ... each with at least this many votes. 1 lets the votes only rank
	 * and the check decide: under hard light the right keyframe led the
	 * votes with 8-14. Only for a channel whose check does not verify
	 * places in another world (config: monochrome 1; every place verified
	 * in another world was an invariant one, docs/localisation.md). */
	int global_min_votes = 15;
	/** A place this localiser verifies (no fix yet) narrows the next frame's
	 * search with its own covariance, as an unconfirmed solve does; the
	 * track that solves are judged against keeps global_sigma added. Off
	 * for a channel whose places alias: their narrow gates held places in
	 * another world. */
	bool place_seeds_search = false;
	/** First pass of a verification: BRIEF in a circle this large around each
	 * landmark's projection from the candidate keyframe's own pose (the live
	 * camera is near it); the second pass is the gate around that solve [px]. */
	double global_window_px = 80.0;
	int global_min_inliers = 30;  //!< a verified place needs this many inliers
	/** Another verified place at least global_distinct_m away with inliers
	 * >= ratio * the best's makes the search ambiguous: no place [-]. */
	double global_ambiguity_ratio = 0.7;
	double global_distinct_m = 3.0;	 //!< see global_ambiguity_ratio [m]

	/** Fault injection (evaluation only): match against the keyframe this many
	 * along the chain from the chosen one (clamped to the chain), reported as
	 * the chosen one; where the clamp lands on the chosen keyframe itself the
	 * frame has no keyframe (docs/localisation.md, "Injected faults"). */
	int fault_keyframe_offset = 0;

	/** Reads `section` (keys as above, with their units) through
	 * core::SettingsSection; unknown keys are errors. */
	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void load(const mrpt::config::CConfigFileBase& c, const std::string& section);
	void dump(std::ostream& out) const;
	void validate() const;	//!< throws std::invalid_argument naming the option
};

/** Options for the channel `channel`: [section], then [section.<channel>]. */
TLocaliserOptions localiserOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& section = "localiser");

/** A fix's covariance: the solver's scaled by cov_scale, raised to the
 * bootstrap's (`samples` resamples; zero = none) in the directions where
 * that is larger beyond chance. Scaling after taking the larger would
 * inflate the bootstrap's empirical spread a second time. */
geometry::Matrix6d fixCovariance(
	const geometry::Matrix6d& solver, const geometry::Matrix6d& bootstrap, double cov_scale, int samples);

/** The VO stages a localiser is made of, configured from its options: the
 * keyframe matcher for a search region, and the pose estimator (solved
 * without the motion prior). Diagnostic tools build the same stages. */
vo::TKeyframeMatcherOptions matcherOptionsFor(const TLocaliserOptions& o, SearchMode mode);
vo::TRelativePoseOptions estimatorOptionsFor(const TLocaliserOptions& o);
/** ... and the accept stage. */
TAcceptanceOptions acceptanceOptionsFor(const TLocaliserOptions& o);

/** One frame's input. */
struct TLocaliserInput
{
	size_t frame = 0;  //!< live frame index
	double timestamp = 0;  //!< [s]
	const features::TStereoFrame* meas = nullptr;  //!< the live frame's measurements of this channel
	geometry::TStereoCalib calib;  //!< the live camera
	/** The system's track propagated to this frame: what a solve is
	 * validated against (invalid: no prior, nothing to do). */
	TKeyframePose prediction;
	/** Where to search, when tighter than the track (an unconfirmed solve's
	 * seed); invalid: the prediction. Never used to validate. */
	TKeyframePose search;
	/** The track is a confirmed place: a consistent solve is a fix at once. */
	bool track_confirmed = false;
	TMotion motion;	 //!< VO's increment (for the frame-to-frame test)
};

enum class LocaliserStatus
{
	Ok,	 //!< accepted fix
	Unconfirmed,  //!< consistent, but fewer than K consistent frames since the last failure
	NoPrediction,  //!< no prior pose: nothing to search around
	NoKeyframe,	 //!< no map keyframe near the prediction (position and heading)
	Lost,  //!< the gates grew past the ceiling: the prediction is too uncertain to search
	FewMatches,
	FewInliers,
	SolverFailed,
	Uncertain,	//!< the fix's covariance exceeds max_sigma_m / max_sigma_deg (when set)
	PredictionInconsistent,	 //!< the fix disagrees with the prediction
	MotionInconsistent,	 //!< its frame-to-frame motion disagrees with VO's
	Contradicted,  //!< accepted, but a more certain fix of the same frame disagrees (the system's cross-check)
	NotRun	//!< the joint localiser, not run: each of its channels' own fixes was accepted (`joint_only_where_a_channel_fails`)
};
std::string toString(LocaliserStatus s);

/** A correspondence's live measurement, as a picture of the frame draws it. */
struct TLiveMatch
{
	float u = 0, v = 0;	 //!< in the live left image [px]
	bool inlier = false;  //!< kept by the final solve
};

/** One localiser's result for one frame (shaped like MOLA's localisation
 * update: timestamp, reference, relative pose, covariance, quality). */
struct TLocaliserResult
{
	size_t frame = 0;
	double timestamp = 0;  //!< [s]
	std::string channel;
	LocaliserStatus status = LocaliserStatus::NoPrediction;
	bool solved = false;  //!< a pose was solved (T_kf_live, cov meaningful)
	bool accepted() const { return status == LocaliserStatus::Ok; }
	/** The solve as a pose in its keyframe (invalid when nothing was solved). */
	TKeyframePose pose() const
	{
		TKeyframePose p;
		p.valid = solved;
		p.kf = kf_id;
		p.T_kf_live = T_kf_live;
		p.cov = cov;
		return p;
	}
	uint32_t kf_id = 0;	 //!< the keyframe localised against
	uint16_t kf_run = 0;  //!< its survey run (CKeyframeMap::runs())
	uint64_t kf_frame = 0;	//!< its frame in the survey run
	double kf_stamp = 0;  //!< its timestamp [s]
	Eigen::Isometry3d T_kf_live = Eigen::Isometry3d::Identity();  //!< live left camera in the keyframe's [m]
	geometry::Matrix6d cov = geometry::Matrix6d::Zero();  //!< of T_kf_live (scaled by cov_scale)
	int matches = 0;  //!< correspondences after refinement
	int warped = 0;	 //!< ... of them found through a landmark's warp (warp_patches)
	int patch_matches = 0;	//!< ... of them found by the patch pass (patch_search)
	int inliers = 0;
	double rms_px = 0;
	/** A posteriori variance factor of the solve: the inliers' whitened
	 * squared residuals over the redundancy (about 1 when sigma_px is right) [-]. */
	double var_factor = -1;
	double sigma_m = -1, sigma_deg = -1;  //!< largest standard deviation of the fix (scaled) [m], [deg]
	double prediction_d2 = -1;	//!< Mahalanobis distance^2 of the prediction test (-1: not run)
	double motion_d2 = -1;	//!< ... of the motion test (-1: not run)
	int consistent = 0;	 //!< consecutive consistent frames so far
	vo::TGateStats gate;
	double ms = 0;	//!< time of this localiser on this frame [ms]
	/** Where that time went [ms]: the descriptor search of the local map
	 * (both gate attempts), its RANSAC and robust solve, the patch pass's
	 * search and solve, the fix's covariance (the bootstrap). */
	struct TStageMs
	{
		double search = 0, solve = 0, patch_search = 0, patch_solve = 0, covariance = 0;
	} ms_stage;
	/** The last search's correspondences, inliers of its solve marked (none
	 * without a search): what `shadyloc localise --gif` draws. */
	std::vector<TLiveMatch> live_matches;
};

/** What a localiser's search found on one frame, solved or not: the
 * correspondences of its last search (refined, the patch pass's included),
 * in keyframe kf's frame. Empty when it did not search (no keyframe, lost).
 * The joint localiser solves the union of several channels' (JointLocaliser.h). */
struct TSearchedCorrespondences
{
	uint32_t kf = 0;
	std::vector<geometry::TStereoCorrespondence> corr;
	/** corr[patch_from..] are the patch pass's (none when past the end):
	 * found where this channel's own solve (or the prediction) put them, so
	 * they confirm that pose whether it is right or not. */
	size_t patch_from = std::numeric_limits<size_t>::max();
};

/** A place found by the global search. */
struct TGlobalPlace
{
	bool ok = false;  //!< a verified, unambiguous place
	std::string why;  //!< when not ok: why not
	TKeyframePose pose;	 //!< the live camera in the place's keyframe
	int inliers = 0, votes = 0;
	int matches = 0;  //!< the verified solve's correspondences
	int runner_up_inliers = 0;	//!< best verified place elsewhere (ambiguity)
	int verified = 0;  //!< candidates verified
	bool certain = false;  //!< its covariance within the fix bounds (max_sigma_m, max_sigma_deg)
};

class StereoLocaliser
{
   public:
	/** `channel` names one of the map's channels (throws naming the map's
	 * channels if absent). The map must outlive the localiser, unchanged
	 * while it localises (its descriptors are indexed here, once). */
	StereoLocaliser(const CKeyframeMap& map, const std::string& channel, const TLocaliserOptions& o);

	/** One frame (see the file comment). Keeps the state of the failure test.
	 * With `searched`, also what the search found (for a joint solve). */
	TLocaliserResult localise(const TLocaliserInput& in, TSearchedCorrespondences* searched = nullptr);

	/** A place for the live frame with no prior. Const: one instance may run
	 * it while another thread uses a different localiser. */
	TGlobalPlace globalSearch(const features::TStereoFrame& meas, const geometry::TStereoCalib& calib, uint32_t seed) const;
	/** The same among the given keyframes only (e.g. around a start keyframe).
	 * With `guess` (the live camera in the map frame, e.g. dead reckoning
	 * after a loss), each candidate is first matched where the guess projects
	 * its landmarks, through their warps (a live run to the side of the
	 * survey), and then, if that fails, as if the camera were at the
	 * keyframe. */
	TGlobalPlace globalSearch(
		const features::TStereoFrame& meas, const geometry::TStereoCalib& calib, uint32_t seed,
		const std::vector<uint32_t>& among, const std::optional<Eigen::Isometry3d>& guess = std::nullopt) const;

	/** Forgets the previous solve and confirmation (a new start). */
	void reset();
	/** The system rejected this frame's accepted solve (contradicted): it
	 * is no reference, and consistency starts again. */
	void forgetSolve() { m_accept.noSolve(); }
	/** A verified place at `frame` (the global search): the first consistent
	 * frame of the new hypothesis. */
	void startFrom(size_t frame, const TKeyframePose& place) { m_accept.startFrom(frame, place); }

	const std::string& channel() const { return m_channel; }
	const TLocaliserOptions& options() const { return m_opts; }
	/** T_a_b with covariance through the chain, or through map poses plus
	 * the cross-segment covariance when a and b are in different segments
	 * (the link its acceptance tests use). */
	geometry::TPoseWithCov between(uint32_t a, uint32_t b) const;

   private:
	/** The keyframe to localise against and the prediction in it; invalid if none. */
	TKeyframePose chooseKeyframe(const TKeyframePose& pred) const;
	/** chooseKeyframe's keyframe, then that of each other experience with
	 * one in range, nearest first: at most kf_experiences_per_frame. */
	std::vector<TKeyframePose> chooseKeyframes(const TKeyframePose& pred) const;
	/** One experience's search and solve around `pred` (fault injection
	 * applied), on a copy of the frame's result `r0`. */
	struct TSearchAttempt
	{
		bool tried = false;
		LocaliserStatus status = LocaliserStatus::NoKeyframe;
		TLocaliserResult r;
		vo::TKeyframeMatchOutput mo;
		vo::TRelativePoseOutput po;
	};
	TSearchAttempt searchAttempt(const TLocaliserInput& in, const TKeyframePose& pred, const TLocaliserResult& r0) const;
	/** The local map's keyframes around `ref` (ref first, then by distance
	 * from the predicted camera). */
	std::vector<uint32_t> window(uint32_t ref, const Eigen::Isometry3d& T_map_pred) const;
	/** Searches the window's landmarks around the prediction `pred` (in
	 * `ref`) with the prediction's covariance scaled by gateScale^2: the
	 * correspondences in ref's frame, each live measurement at most once. */
	void searchLocalMap(
		const TLocaliserInput& in, uint32_t ref, const TKeyframePose& pred, double gateScale,
		vo::TKeyframeMatchOutput& out, std::vector<uint32_t>& keyframeOf) const;
	/** The second pass at a solved pose T_curr_ref: the window's landmarks
	 * not yet matched (keyframeOf / out.landmark) searched by projection with
	 * their patches (KeyframeMatcher::searchPatches); appends to out. */
	void searchLocalMapByPatches(
		const TLocaliserInput& in, uint32_t ref, const Eigen::Isometry3d& T_curr_ref,
		vo::TKeyframeMatchOutput& out, std::vector<uint32_t>& keyframeOf) const;
	/** Search (once more with wider gates when the first finds too few) and
	 * solve without the prior; fills r's search figures. */
	LocaliserStatus searchAndSolve(
		const TLocaliserInput& in, uint32_t ref, const TKeyframePose& pred, vo::TKeyframeMatchOutput& mo,
		vo::TRelativePoseOutput& po, TLocaliserResult& r) const;

	/** A place the global search verified: its solve and correspondences. */
	struct TVerifiedPlace
	{
		uint32_t kf = 0;
		int inliers = 0, votes = 0;
		Eigen::Isometry3d T_kf_live, T_map_live;
		vo::TRelativePoseOutput solve;
		std::vector<geometry::TStereoCorrespondence> corr;	//!< the solve's
	};
	/** BRIEF voting: each live descriptor votes for the keyframe of `among`
	 * holding its nearest landmark (within global_vote_hamming). (-votes, id),
	 * most votes first, then the smaller id. */
	std::vector<std::pair<int, uint32_t>> placeVotes(
		const features::TStereoFrame& meas, const std::vector<uint32_t>& among) const;
	/** Keyframe k verified as the live frame's place: matched around `guess`
	 * (if any) or its own view, solved, searched again around that pose (and
	 * by patches), solved again; none when no solve reaches min_inliers.
	 * `solves` counts the solves tried. */
	std::optional<TVerifiedPlace> verifyPlace(
		const features::TStereoFrame& meas, const geometry::TStereoCalib& calib, uint32_t seed, uint32_t k,
		const std::optional<Eigen::Isometry3d>& guess, int& solves) const;
	/** The best of the verified places as the search's result. */
	TGlobalPlace bestPlace(
		const std::vector<TVerifiedPlace>& ver, const geometry::TStereoCalib& calib, uint32_t seed) const;
	/** Moves the candidate keyframe nearest `guess` (T_map_live) to the front. */
	void putNearestFirst(const Eigen::Isometry3d& guess, std::vector<std::pair<int, uint32_t>>& candidates) const;
	/** The map channel's BRIEF pattern, for warped descriptors; null when
	 * the channel holds ORB descriptors (oriented tests: not warped). */
	const features::BriefExtractor* briefPattern() const;

	const CKeyframeMap& m_map;
	std::string m_channel;
	TLocaliserOptions m_opts;
	vo::KeyframeMatcher m_matcher;	 //!< options.search's region
	vo::KeyframeMatcher m_gateMatcher;	 //!< global search, second pass
	vo::KeyframeMatcher m_placeMatcher;  //!< global search, first pass (window around the keyframe's view)
	vo::RelativePoseEstimator m_estimator;
	features::BriefExtractor m_brief;  //!< the map channel's BRIEF pattern (warped matching)
	FixAcceptance m_accept;  //!< the failure test and its state
	features::DescriptorGroups m_placeIndex;  //!< the channel's landmark descriptors by keyframe (the place vote)
};

}  // namespace shadyloc::localisation
