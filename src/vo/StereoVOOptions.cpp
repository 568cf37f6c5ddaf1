/* ShadyLoc — options of the stereo VO ([vo] in config/vo.ini). */
#include <shadyloc/core/Settings.h>
#include <shadyloc/vo/StereoVO.h>
#include <shadyloc/vo/VOConfig.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <filesystem>

#include <algorithm>
#include <ostream>
#include <stdexcept>

namespace shadyloc::vo
{
// ---- options ------------------------------------------------------------------
/** Keys renamed to carry their unit (the members keep their names). */
static const std::vector<core::TRenamedKey> kRenamedVOKeys = {
	{"refine_radius", "refine_radius_px"},
	{"near_min_disparity", "near_min_disparity_px"},
	{"kf_translation", "kf_translation_m"},
	{"max_step_translation", "max_step_translation_m"},
};

void TStereoVOOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::SettingsSection r(c, s);
	r.renamed(kRenamedVOKeys);
	// Read from [vo] by the commands: `channel` picks the channel (filters::channelFromConfig);
	// `channel_order` moved to the channel's filter section and is refused there, naming it.
	r.alsoKnown({"channel", "channel_order"});
	r.read("search_radius_px", search_radius_px);
	r.read("search_radius_lost_px", search_radius_lost_px);
	r.read("max_hamming", max_hamming);
	r.read("match_ratio", match_ratio);
	r.read("refine_min_zncc", refine_min_zncc);
	r.read("refine_radius_px", refine_radius);
	r.read("refine_iterations", refine_iterations);
	r.read("min_stereo", min_stereo);
	r.read("min_matches", min_matches);
	r.read("min_inliers", min_inliers);
	r.read("near_min_disparity_px", near_min_disparity);
	r.read("near_min_matches", near_min_matches);
	r.read("ransac_threshold_px", ransac_threshold_px);
	r.read("ransac_iterations", ransac_iterations);
	r.read("sigma_px", sigma_px);
	r.read("huber_k", huber_k);
	r.read("kf_translation_m", kf_translation);
	r.read("kf_rotation_deg", kf_rotation_deg);
	r.read("kf_min_tracked_fraction", kf_min_tracked_fraction);
	r.read("kf_min_inliers", kf_min_inliers);
	r.read("max_step_translation_m", max_step_translation);
	r.read("max_step_rotation_deg", max_step_rotation_deg);
	r.read("max_lost_frames", max_lost_frames);
	r.read("constant_velocity", constant_velocity);
	r.read("two_view_ba", two_view_ba);
	r.read("ransac_prediction", ransac_prediction);
	r.read("ransac_prior_sigma_m", ransac_prior_sigma_m);
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

void TStereoVOOptions::dumpToTextStream(std::ostream& o) const
{
	core::SettingsWriter w(o);
	w.value("search_radius_px", search_radius_px, "BRIEF search window around each predicted projection [px]");
	w.value("search_radius_lost_px", search_radius_lost_px, "window after a failure [px]");
	w.value("max_hamming", max_hamming, "largest BRIEF distance of a match [bits of 256]");
	w.value("match_ratio", match_ratio, "best < ratio * second best distance");
	w.value("refine_min_zncc", refine_min_zncc, "patch refinement correlation");
	w.value("refine_radius_px", refine_radius, "[px]");
	w.value("refine_iterations", refine_iterations, "Gauss-Newton steps, 0 = parabola only");
	w.value("min_stereo", min_stereo);
	w.value("min_matches", min_matches);
	w.value("min_inliers", min_inliers);
	w.value("near_min_disparity_px", near_min_disparity,
			"far landmarks left out of the solve when enough near ones, 0 = off [px]");
	w.value("near_min_matches", near_min_matches);
	w.value("ransac_threshold_px", ransac_threshold_px, "[px]");
	w.value("ransac_iterations", ransac_iterations);
	w.value("sigma_px", sigma_px, "[px]");
	w.value("huber_k", huber_k, "[sigmas]");
	w.value("kf_translation_m", kf_translation, "[m]");
	w.value("kf_rotation_deg", kf_rotation_deg, "[deg]");
	w.value("kf_min_tracked_fraction", kf_min_tracked_fraction);
	w.value("kf_min_inliers", kf_min_inliers);
	w.value("max_step_translation_m", max_step_translation, "[m]");
	w.value("max_step_rotation_deg", max_step_rotation_deg, "[deg]");
	w.value("max_lost_frames", max_lost_frames);
	w.value("constant_velocity", constant_velocity, "predict with the last motion (else identity)");
	w.value("two_view_ba", two_view_ba, "solve by two-view bundle adjustment");
	w.value("ransac_prediction", ransac_prediction, "the prediction is a RANSAC hypothesis");
	w.value("ransac_prior_sigma_m", ransac_prior_sigma_m,
			"preference for hypotheses near the prediction, 0 = off [m]");
}

void TStereoVOOptions::validate() const
{
	// Messages use the .ini key names.
	auto bad = [](const std::string& w) { throw std::invalid_argument("option " + w); };
	if (!(search_radius_px > 0) || search_radius_lost_px < search_radius_px)
		bad("search_radius_px must be > 0 and <= search_radius_lost_px");
	if (max_hamming < 1 || max_hamming > 256) bad("max_hamming must be in [1,256]");
	if (!(match_ratio > 0 && match_ratio <= 1)) bad("match_ratio must be in (0,1]");
	if (refine_radius < 0 || refine_radius > 4) bad("refine_radius_px must be in [0,4]");
	if (refine_iterations < 0 || refine_iterations > 20) bad("refine_iterations must be in [0,20]");
	if (min_inliers < 3 || min_matches < min_inliers) bad("need 3 <= min_inliers <= min_matches");
	if (!(near_min_disparity >= 0) || near_min_matches < min_matches)
		bad("near_min_disparity_px must be >= 0 and near_min_matches >= min_matches");
	if (!(ransac_threshold_px > 0) || ransac_iterations < 1) bad("ransac_threshold_px/iterations must be > 0");
	if (!(sigma_px > 0) || !(huber_k > 0)) bad("sigma_px and huber_k must be > 0");
	if (!(kf_translation > 0) || !(kf_rotation_deg > 0)) bad("kf_translation_m/kf_rotation_deg must be > 0");
	if (!(max_step_translation > 0) || !(max_step_rotation_deg > 0))
		bad("max_step_translation_m/max_step_rotation_deg must be > 0");
	if (max_lost_frames < 0) bad("max_lost_frames must be >= 0");
	if (!(ransac_prior_sigma_m >= 0)) bad("ransac_prior_sigma_m must be >= 0 (0 = off)");
}

// ---- the config file ------------------------------------------------------------
const std::vector<std::string>& voConfigSections()
{
	static const std::vector<std::string> s = {
		"vo",  "vo.mono",  "vo.invariant", "features", "features.mono", "features.invariant",
		"mono", "invariant", "filters", "map"};
	return s;
}

std::vector<std::string> voConfigSectionsOf(const mrpt::config::CConfigFileBase& cfg)
{
	std::vector<std::string> known = voConfigSections(), all;
	cfg.getAllSections(all);
	for (const auto& s : all)
		if (!s.empty() && cfg.keyExists(s, "class"))
			for (const std::string& k : {s, "vo." + s, "features." + s})
				if (std::find(known.begin(), known.end(), k) == known.end()) known.push_back(k);
	return known;
}

void checkVOConfigSections(const mrpt::config::CConfigFileBase& cfg)
{
	core::checkSections(cfg, voConfigSectionsOf(cfg), "VO config");
}

std::unique_ptr<mrpt::config::CConfigFileBase> loadVOConfig(const std::string& path)
{
	if (path.empty()) return std::make_unique<mrpt::config::CConfigFileMemory>("");
	if (!std::filesystem::exists(path)) throw std::runtime_error("config file '" + path + "' does not exist");
	auto cfg = std::make_unique<mrpt::config::CConfigFile>(path);
	checkVOConfigSections(*cfg);
	return cfg;
}

}  // namespace shadyloc::vo
