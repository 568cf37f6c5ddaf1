/* ShadyLoc — options of a localiser ([localiser], [localiser.<channel>]). */
#include <shadyloc/core/Settings.h>
#include <shadyloc/localisation/StereoLocaliser.h>

#include <stdexcept>

namespace shadyloc::localisation
{
void TLocaliserOptions::load(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::SettingsSection r(c, s);
	r.read("kf_back_m", kf_back_m);
	r.read("kf_ahead_m", kf_ahead_m);
	r.read("kf_lookahead_m", kf_lookahead_m);
	r.read("kf_max_distance_m", kf_max_distance_m);
	r.read("kf_window_m", kf_window_m);
	r.read("kf_window_max", kf_window_max);
	r.read("kf_max_angle_deg", kf_max_angle_deg);
	r.read("kf_angle_weight_m_per_deg", kf_angle_weight_m_per_deg);
	r.read("cross_segment_sigma_m", cross_segment_sigma_m);
	r.read("cross_segment_sigma_deg", cross_segment_sigma_deg);
	r.readChoice<SearchMode>(
		"search", search, {{"gate", SearchMode::Gate}, {"window", SearchMode::Window}, {"global", SearchMode::Global}});
	r.read("gate_chi2", gate_chi2);
	r.read("gate_min_px", gate_min_px);
	r.read("gate_max_px", gate_max_px);
	r.read("gate_landmark_max_px", gate_landmark_max_px);
	r.read("max_overflow_fraction", max_overflow_fraction);
	r.read("retry_gate_scale", retry_gate_scale);
	r.read("window_px", window_px);
	r.read("max_hamming", max_hamming);
	r.read("warp_patches", warp_patches);
	r.read("warp_min_distortion", warp_min_distortion);
	r.read("patch_search", patch_search);
	r.read("patch_search_radius_px", patch_search_radius_px);
	r.read("patch_search_from_prediction", patch_search_from_prediction);
	r.read("patch_min_zncc", patch_min_zncc);
	r.read("patch_prediction_max_sigma_m", patch_prediction_max_sigma_m);
	r.read("patch_prediction_min_descriptor_inliers", patch_prediction_min_descriptor_inliers);
	r.read("match_ratio", match_ratio);
	r.read("refine_min_zncc", refine_min_zncc);
	r.read("refine_radius_px", refine_radius_px);
	r.read("refine_iterations", refine_iterations);
	r.read("ransac_threshold_px", ransac_threshold_px);
	r.read("ransac_iterations", ransac_iterations);
	r.read("sigma_px", sigma_px);
	r.read("huber_k", huber_k);
	r.read("two_view_ba", two_view_ba);
	r.read("min_matches", min_matches);
	r.read("min_inliers", min_inliers);
	r.read("cov_scale", cov_scale);
	r.read("bootstrap_samples", bootstrap_samples);
	r.read("max_sigma_m", max_sigma_m);
	r.read("max_sigma_deg", max_sigma_deg);
	r.read("uncertain_breaks_chain", uncertain_breaks_chain);
	r.read("prediction_chi2", prediction_chi2);
	r.read("motion_chi2", motion_chi2);
	r.read("consistent_frames", consistent_frames);
	r.read("global_vote_hamming", global_vote_hamming);
	r.read("global_candidates", global_candidates);
	r.read("global_window_px", global_window_px);
	r.read("global_min_inliers", global_min_inliers);
	r.read("global_ambiguity_ratio", global_ambiguity_ratio);
	r.read("global_distinct_m", global_distinct_m);
	r.read("fault_keyframe_offset", fault_keyframe_offset);
	r.finish();
	try
	{
		validate();
	}
	catch (const std::exception& e)
	{
		throw core::SettingsError(r.where() + " " + e.what());
	}
}

void TLocaliserOptions::dump(std::ostream& out) const
{
	core::SettingsWriter w(out);
	w.value("kf_back_m", kf_back_m, "keyframes considered behind the predicted one along the chain [m]");
	w.value("kf_ahead_m", kf_ahead_m, "... and ahead of it [m]");
	w.value("kf_lookahead_m", kf_lookahead_m, "the keyframe nearest this point in front of the camera [m]");
	w.value("kf_max_distance_m", kf_max_distance_m, "[m]");
	w.value("kf_window_m", kf_window_m, "local map: keyframes along the chain within this of the chosen one (0 = it alone) [m]");
	w.value("kf_window_max", kf_window_max, "... at most this many");
	w.value("kf_max_angle_deg", kf_max_angle_deg, "optical axes within this [deg]");
	w.value("kf_angle_weight_m_per_deg", kf_angle_weight_m_per_deg, "[m/deg]");
	w.value("cross_segment_sigma_m", cross_segment_sigma_m, "[m]");
	w.value("cross_segment_sigma_deg", cross_segment_sigma_deg, "[deg]");
	w.value("search", toString(search), "gate | window | global");
	w.value("gate_chi2", gate_chi2, "chi^2, 3 dof");
	w.value("gate_min_px", gate_min_px, "[px]");
	w.value("gate_max_px", gate_max_px, "ceiling: lost rather than clipped [px]");
	w.value("gate_landmark_max_px", gate_landmark_max_px, "with the landmark's own uncertainty (0 = gate_max_px bounds all) [px]");
	w.value("max_overflow_fraction", max_overflow_fraction);
	w.value("retry_gate_scale", retry_gate_scale);
	w.value("window_px", window_px, "[px]");
	w.value("max_hamming", max_hamming, "[bits of 256]");
	w.value("warp_patches", warp_patches, "match through each landmark's plane-induced warp at the predicted pose");
	w.value("warp_min_distortion", warp_min_distortion, "... where it moves pixel offsets by more than this share");
	w.value("patch_search", patch_search, "after a solve, search unmatched landmarks by projection with their patches, solve again");
	w.value("patch_search_radius_px", patch_search_radius_px, "... the patch climbs at most this far from the projection [px]");
	w.value("patch_min_zncc", patch_min_zncc, "... and must correlate this well there");
	w.value("patch_prediction_max_sigma_m", patch_prediction_max_sigma_m, "... or at a prediction this certain (a place just verified) [m]");
	w.value("patch_prediction_min_descriptor_inliers", patch_prediction_min_descriptor_inliers, "... and its solve must keep this many descriptor matches as inliers");
	w.value("patch_search_from_prediction", patch_search_from_prediction, "... and at the prediction of a confirmed track when descriptors find too few");
	w.value("match_ratio", match_ratio);
	w.value("refine_min_zncc", refine_min_zncc);
	w.value("refine_radius_px", refine_radius_px, "[px]");
	w.value("refine_iterations", refine_iterations);
	w.value("ransac_threshold_px", ransac_threshold_px, "[px]");
	w.value("ransac_iterations", ransac_iterations);
	w.value("sigma_px", sigma_px, "[px]");
	w.value("huber_k", huber_k, "[sigmas]");
	w.value("two_view_ba", two_view_ba);
	w.value("min_matches", min_matches);
	w.value("min_inliers", min_inliers);
	w.value("cov_scale", cov_scale, "the solver's covariance is scaled by this");
	w.value("bootstrap_samples", bootstrap_samples, "resamples of the inliers for the bootstrap covariance (0 = off)");
	w.value("max_sigma_m", max_sigma_m, "a fix less certain than this is not used (0 = no cap) [m]");
	w.value("max_sigma_deg", max_sigma_deg, "(0 = no cap) [deg]");
	w.value("uncertain_breaks_chain", uncertain_breaks_chain, "an uncertain solve needs K consistent frames again");
	w.value("prediction_chi2", prediction_chi2, "chi^2, 6 dof");
	w.value("motion_chi2", motion_chi2, "chi^2, 6 dof");
	w.value("consistent_frames", consistent_frames, "K");
	w.value("global_vote_hamming", global_vote_hamming, "[bits]");
	w.value("global_candidates", global_candidates);
	w.value("global_window_px", global_window_px, "first pass of a verification [px]");
	w.value("global_min_inliers", global_min_inliers);
	w.value("global_ambiguity_ratio", global_ambiguity_ratio);
	w.value("global_distinct_m", global_distinct_m, "[m]");
	w.value("fault_keyframe_offset", fault_keyframe_offset, "fault injection, 0 = off");
}

void TLocaliserOptions::validate() const
{
	auto need = [](bool ok, const char* key, const char* what) {
		if (!ok) throw std::invalid_argument(std::string(key) + ": " + what);
	};
	need(kf_back_m >= 0, "kf_back_m", "must be >= 0");
	need(kf_ahead_m >= 0, "kf_ahead_m", "must be >= 0");
	need(kf_max_distance_m > 0, "kf_max_distance_m", "must be > 0");
	need(kf_window_m >= 0, "kf_window_m", "must be >= 0");
	need(kf_window_max >= 1 && kf_window_max <= 20, "kf_window_max", "must be in [1, 20]");
	need(kf_max_angle_deg > 0 && kf_max_angle_deg <= 180, "kf_max_angle_deg", "must be in (0, 180]");
	need(kf_angle_weight_m_per_deg >= 0, "kf_angle_weight_m_per_deg", "must be >= 0");
	need(cross_segment_sigma_m > 0, "cross_segment_sigma_m", "must be > 0");
	need(cross_segment_sigma_deg > 0, "cross_segment_sigma_deg", "must be > 0");
	need(gate_chi2 > 0, "gate_chi2", "must be > 0");
	need(gate_min_px > 0, "gate_min_px", "must be > 0");
	need(gate_max_px > gate_min_px, "gate_max_px", "must exceed gate_min_px");
	need(gate_landmark_max_px == 0 || (gate_landmark_max_px >= gate_max_px && gate_landmark_max_px <= 10000),
		 "gate_landmark_max_px", "must be 0 (off) or in [gate_max_px, 10000]");
	need(max_overflow_fraction >= 0 && max_overflow_fraction <= 1, "max_overflow_fraction", "must be in [0, 1]");
	need(retry_gate_scale >= 1, "retry_gate_scale", "must be >= 1");
	need(window_px > 0, "window_px", "must be > 0");
	need(max_hamming > 0 && max_hamming <= 256, "max_hamming", "must be in (0, 256]");
	need(patch_prediction_max_sigma_m >= 0 && patch_prediction_max_sigma_m <= 10, "patch_prediction_max_sigma_m", "must be in [0, 10] [m]");
	need(patch_prediction_min_descriptor_inliers >= 0, "patch_prediction_min_descriptor_inliers", "must be >= 0");
	need(patch_min_zncc > 0 && patch_min_zncc <= 1, "patch_min_zncc", "must be in (0, 1]");
	need(patch_search_radius_px >= 0 && patch_search_radius_px <= 10, "patch_search_radius_px", "must be in 0..10 [px]");
	need(warp_min_distortion >= 0 && warp_min_distortion <= 10, "warp_min_distortion", "must be in [0, 10]");
	need(match_ratio > 0 && match_ratio <= 1, "match_ratio", "must be in (0, 1]");
	need(refine_min_zncc >= -1 && refine_min_zncc <= 1, "refine_min_zncc", "must be in [-1, 1]");
	need(refine_radius_px >= 0, "refine_radius_px", "must be >= 0");
	need(refine_iterations >= 0, "refine_iterations", "must be >= 0");
	need(ransac_threshold_px > 0, "ransac_threshold_px", "must be > 0");
	need(ransac_iterations > 0, "ransac_iterations", "must be > 0");
	need(sigma_px > 0, "sigma_px", "must be > 0");
	need(huber_k > 0, "huber_k", "must be > 0");
	need(min_matches >= 3, "min_matches", "must be >= 3");
	need(min_inliers >= 3, "min_inliers", "must be >= 3");
	need(cov_scale >= 1, "cov_scale", "must be >= 1");
	need(bootstrap_samples == 0 || (bootstrap_samples >= 2 && bootstrap_samples <= 1000), "bootstrap_samples", "must be 0 (off) or 2..1000");
	need(max_sigma_m >= 0, "max_sigma_m", "must be >= 0 (0 = no cap)");
	need(max_sigma_deg >= 0, "max_sigma_deg", "must be >= 0 (0 = no cap)");
	need(global_window_px > 0, "global_window_px", "must be > 0");
	need(prediction_chi2 > 0, "prediction_chi2", "must be > 0");
	need(motion_chi2 > 0, "motion_chi2", "must be > 0");
	need(consistent_frames >= 0, "consistent_frames", "must be >= 0");
	need(global_vote_hamming > 0 && global_vote_hamming <= 256, "global_vote_hamming", "must be in (0, 256]");
	need(global_candidates >= 1, "global_candidates", "must be >= 1");
	need(global_min_inliers >= 3, "global_min_inliers", "must be >= 3");
	need(global_ambiguity_ratio > 0 && global_ambiguity_ratio <= 1, "global_ambiguity_ratio", "must be in (0, 1]");
	need(global_distinct_m > 0, "global_distinct_m", "must be > 0");
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
