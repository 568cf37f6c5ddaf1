/* ShadyLoc — options of the stereo VO ([vo] in config/vo.ini). */
#include <shadyloc/core/Options.h>
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

void TStereoVOOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	v.renamed(kRenamedVOKeys);
	// Read from [vo] by the commands: `channel` picks the channel (filters::channelFromConfig);
	// `channel_order` moved to the channel's filter section and is refused there, naming it.
	v.alsoKnown({"channel", "channel_order"});
	v("search_radius_px", search_radius_px, "px", Range::above(0), "BRIEF search window around each predicted projection");
	v("search_radius_lost_px", search_radius_lost_px, "px", Range::any(), "window after a failure");
	v("max_hamming", max_hamming, "bits of 256", Range::closed(1, 256), "largest BRIEF distance of a match");
	v("match_ratio", match_ratio, "", Range::openClosed(0, 1), "best < ratio * second best distance");
	v("refine_min_zncc", refine_min_zncc, "", Range::any(), "patch refinement correlation");
	v("refine_radius_px", refine_radius, "px", Range::closed(0, 4), "");
	v("refine_iterations", refine_iterations, "", Range::closed(0, 20), "Gauss-Newton steps, 0 = parabola only");
	v("min_stereo", min_stereo, "", Range::any(), "");
	v("min_matches", min_matches, "", Range::any(), "");
	v("min_inliers", min_inliers, "", Range::atLeast(3), "");
	v("near_min_disparity_px", near_min_disparity, "px", Range::atLeast(0),
	  "far landmarks left out of the solve when enough near ones, 0 = off");
	v("near_min_matches", near_min_matches, "", Range::any(), "");
	v("ransac_threshold_px", ransac_threshold_px, "px", Range::above(0), "");
	v("ransac_iterations", ransac_iterations, "", Range::atLeast(1), "");
	v("sigma_px", sigma_px, "px", Range::above(0), "");
	v("huber_k", huber_k, "sigmas", Range::above(0), "");
	v("kf_translation_m", kf_translation, "m", Range::above(0), "");
	v("kf_rotation_deg", kf_rotation_deg, "deg", Range::above(0), "");
	v("kf_min_tracked_fraction", kf_min_tracked_fraction, "", Range::any(), "");
	v("kf_min_inliers", kf_min_inliers, "", Range::any(), "");
	v("max_step_translation_m", max_step_translation, "m", Range::above(0), "");
	v("max_step_rotation_deg", max_step_rotation_deg, "deg", Range::above(0), "");
	v("max_lost_frames", max_lost_frames, "", Range::atLeast(0), "");
	v("constant_velocity", constant_velocity, "", Range::any(), "predict with the last motion (else identity)");
	v("two_view_ba", two_view_ba, "", Range::any(), "solve by two-view bundle adjustment");
	v("ransac_prediction", ransac_prediction, "", Range::any(), "the prediction is a RANSAC hypothesis");
	v("ransac_prior_sigma_m", ransac_prior_sigma_m, "m", Range::atLeast(0),
	  "preference for hypotheses near the prediction, 0 = off");
}

void TStereoVOOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::loadKeys(*this, c, s);
}

void TStereoVOOptions::dumpToTextStream(std::ostream& o) const { core::dumpKeys(*this, o); }

void TStereoVOOptions::validate() const
{
	core::checkKeys(*this);
	auto need = [](bool ok, const char* what) {
		if (!ok) throw std::invalid_argument(what);
	};
	need(search_radius_lost_px >= search_radius_px, "search_radius_lost_px: must be >= search_radius_px");
	need(min_matches >= min_inliers, "min_matches: must be >= min_inliers");
	need(near_min_matches >= min_matches, "near_min_matches: must be >= min_matches");
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
