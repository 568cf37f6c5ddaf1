/* ShadyLoc — options of a localiser ([localiser], [localiser.<channel>]). */
#include <shadyloc/core/Options.h>
#include <shadyloc/localisation/StereoLocaliser.h>

#include <stdexcept>

namespace shadyloc::localisation
{
void TLocaliserOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	v("kf_back_m", kf_back_m, "m", Range::atLeast(0), "keyframes considered behind the predicted one along the chain");
	v("kf_ahead_m", kf_ahead_m, "m", Range::atLeast(0), "... and ahead of it");
	v("kf_lookahead_m", kf_lookahead_m, "m", Range::any(), "the keyframe nearest this point in front of the camera");
	v("kf_max_distance_m", kf_max_distance_m, "m", Range::above(0), "");
	v("kf_window_m", kf_window_m, "m", Range::atLeast(0),
	  "local map: keyframes along the chain within this of the chosen one (0 = it alone)");
	v("kf_window_max", kf_window_max, "", Range::closed(1, 20), "... at most this many");
	v("kf_max_angle_deg", kf_max_angle_deg, "deg", Range::openClosed(0, 180), "optical axes within this");
	v("kf_angle_weight_m_per_deg", kf_angle_weight_m_per_deg, "m/deg", Range::atLeast(0), "");
	v("kf_stay_in_experience", kf_stay_in_experience, "", Range::any(),
	  "several experiences: the prediction's while it has a keyframe in range");
	v("kf_experiences_per_frame", kf_experiences_per_frame, "", Range::closed(1, 16),
	  "... and up to this many experiences searched per frame, the solve with most inliers kept");
	v("cross_segment_sigma_m", cross_segment_sigma_m, "m", Range::above(0), "");
	v("cross_segment_sigma_deg", cross_segment_sigma_deg, "deg", Range::above(0), "");
	v.choice("search", search, {{"gate", SearchMode::Gate}, {"window", SearchMode::Window}, {"global", SearchMode::Global}},
			 "gate | window | global");
	v("gate_chi2", gate_chi2, "", Range::above(0), "chi^2, 3 dof");
	v("gate_min_px", gate_min_px, "px", Range::above(0), "");
	v("gate_max_px", gate_max_px, "px", Range::any(), "ceiling: lost rather than clipped");
	v("gate_landmark_max_px", gate_landmark_max_px, "px", Range::closed(0, 10000),
	  "with the landmark's own uncertainty (0 = gate_max_px bounds all)");
	v("max_overflow_fraction", max_overflow_fraction, "", Range::closed(0, 1), "");
	v("retry_gate_scale", retry_gate_scale, "", Range::atLeast(1), "");
	v("window_px", window_px, "px", Range::above(0), "");
	v("max_hamming", max_hamming, "bits of 256", Range::openClosed(0, 256), "");
	v("warp_patches", warp_patches, "", Range::any(), "match through each landmark's plane-induced warp at the predicted pose");
	v("warp_min_distortion", warp_min_distortion, "", Range::closed(0, 10),
	  "... where it moves pixel offsets by more than this share");
	v("patch_search", patch_search, "", Range::any(),
	  "after a solve, search unmatched landmarks by projection with their patches, solve again");
	v("patch_search_max_inliers", patch_search_max_inliers, "", Range::atLeast(0),
	  "... only where the descriptor solve keeps fewer inliers than this (0: after every solve)");
	v("patch_search_radius_px", patch_search_radius_px, "px", Range::closed(0, 10),
	  "... the patch climbs at most this far from the projection");
	v("patch_min_zncc", patch_min_zncc, "", Range::openClosed(0, 1), "... and must correlate this well there");
	v("patch_prediction_max_sigma_m", patch_prediction_max_sigma_m, "m", Range::closed(0, 10),
	  "... or at a prediction this certain (a place just verified)");
	v("patch_prediction_min_descriptor_inliers", patch_prediction_min_descriptor_inliers, "", Range::atLeast(0),
	  "... and its solve must keep this many descriptor matches as inliers");
	v("patch_search_from_prediction", patch_search_from_prediction, "", Range::any(),
	  "... and at the prediction of a confirmed track when descriptors find too few");
	v("match_ratio", match_ratio, "", Range::openClosed(0, 1), "");
	v("refine_min_zncc", refine_min_zncc, "", Range::closed(-1, 1), "");
	v("refine_radius_px", refine_radius_px, "px", Range::atLeast(0), "");
	v("refine_iterations", refine_iterations, "", Range::atLeast(0), "");
	v("ransac_threshold_px", ransac_threshold_px, "px", Range::above(0), "");
	v("ransac_iterations", ransac_iterations, "", Range::above(0), "");
	v("sigma_px", sigma_px, "px", Range::above(0), "");
	v("sigma_disparity_px", sigma_disparity_px, "px", Range::atLeast(0),
	  "the disparity's noise beyond sigma_px: uR weighs less in the solve (a channel with poorer stereo)");
	v("huber_k", huber_k, "sigmas", Range::above(0), "");
	v("two_view_ba", two_view_ba, "", Range::any(), "");
	v("min_matches", min_matches, "", Range::atLeast(3), "");
	v("min_inliers", min_inliers, "", Range::atLeast(3), "");
	v("cov_scale", cov_scale, "", Range::atLeast(1), "the solver's covariance is scaled by this");
	v("bootstrap_samples", bootstrap_samples, "", Range::closed(2, 1000).orOff(),
	  "resamples of the inliers for the bootstrap covariance (0 = off)");
	v("bootstrap_relinearise", bootstrap_relinearise, "", Range::any(),
	  "each resample's steps re-linearise (false: the chord method, the solve's Jacobians kept, residuals and Huber weights re-evaluated)");
	v("max_sigma_m", max_sigma_m, "m", Range::atLeast(0), "a fix less certain than this is not used (0 = no cap)");
	v("max_sigma_deg", max_sigma_deg, "deg", Range::atLeast(0), "(0 = no cap)");
	v("uncertain_breaks_chain", uncertain_breaks_chain, "", Range::any(), "an uncertain solve needs K consistent frames again");
	v("prediction_chi2", prediction_chi2, "", Range::above(0), "chi^2, 6 dof");
	v("uncertain_sigma_m", uncertain_sigma_m, "m", Range::atLeast(0),
	  "a solve at least this uncertain must pass the prediction test at uncertain_prediction_chi2 (0 = off)");
	v("uncertain_prediction_chi2", uncertain_prediction_chi2, "", Range::above(0), "chi^2, 6 dof");
	v("motion_chi2", motion_chi2, "", Range::above(0), "chi^2, 6 dof");
	v("consistent_frames", consistent_frames, "", Range::atLeast(0), "K");
	v("global_vote_hamming", global_vote_hamming, "bits", Range::openClosed(0, 256), "");
	v("global_candidates", global_candidates, "", Range::atLeast(1), "");
	v("global_min_votes", global_min_votes, "", Range::atLeast(0),
	  "... each with at least this many votes (1: the check alone decides; only where it verifies nothing in another world)");
	v("place_seeds_search", place_seeds_search, "", Range::any(),
	  "a place this localiser verifies narrows the next search with its own covariance (never validates)");
	v("global_window_px", global_window_px, "px", Range::above(0), "first pass of a verification");
	v("global_min_inliers", global_min_inliers, "", Range::atLeast(3), "");
	v("global_ambiguity_ratio", global_ambiguity_ratio, "", Range::openClosed(0, 1), "");
	v("global_distinct_m", global_distinct_m, "m", Range::above(0), "");
	v("fault_keyframe_offset", fault_keyframe_offset, "", Range::any(), "fault injection, 0 = off");
}

void TLocaliserOptions::load(const mrpt::config::CConfigFileBase& c, const std::string& s) { core::loadKeys(*this, c, s); }

void TLocaliserOptions::dump(std::ostream& out) const { core::dumpKeys(*this, out); }

void TLocaliserOptions::validate() const
{
	core::checkKeys(*this);
	auto need = [](bool ok, const char* what) {
		if (!ok) throw std::invalid_argument(what);
	};
	need(gate_max_px > gate_min_px, "gate_max_px: must exceed gate_min_px");
	need(gate_landmark_max_px == 0 || gate_landmark_max_px >= gate_max_px,
		 "gate_landmark_max_px: must be 0 (off) or in [gate_max_px, 10000]");
}

TLocaliserOptions localiserOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& section)
{
	TLocaliserOptions o;
	if (cfg.sectionExists(section)) o.load(cfg, section);
	const std::string over = section + "." + channel;
	if (cfg.sectionExists(over)) o.load(cfg, over);
	return o;
}

}  // namespace shadyloc::localisation
