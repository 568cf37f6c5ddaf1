/* ShadyLoc — options of the stereo VO ([vo] in config/vo.ini). */
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/config/CConfigFileBase.h>

#include <ostream>
#include <stdexcept>

namespace shadyloc::vo
{
// ---- options ------------------------------------------------------------------
void TStereoVOOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	MRPT_LOAD_CONFIG_VAR(search_radius_px, double, c, s);
	MRPT_LOAD_CONFIG_VAR(search_radius_lost_px, double, c, s);
	MRPT_LOAD_CONFIG_VAR(max_hamming, int, c, s);
	MRPT_LOAD_CONFIG_VAR(match_ratio, double, c, s);
	MRPT_LOAD_CONFIG_VAR(refine_min_zncc, double, c, s);
	MRPT_LOAD_CONFIG_VAR(refine_radius, int, c, s);
	MRPT_LOAD_CONFIG_VAR(refine_iterations, int, c, s);
	MRPT_LOAD_CONFIG_VAR(min_stereo, int, c, s);
	MRPT_LOAD_CONFIG_VAR(min_matches, int, c, s);
	MRPT_LOAD_CONFIG_VAR(min_inliers, int, c, s);
	MRPT_LOAD_CONFIG_VAR(near_min_disparity, double, c, s);
	MRPT_LOAD_CONFIG_VAR(near_min_matches, int, c, s);
	MRPT_LOAD_CONFIG_VAR(ransac_threshold_px, double, c, s);
	MRPT_LOAD_CONFIG_VAR(ransac_iterations, int, c, s);
	MRPT_LOAD_CONFIG_VAR(sigma_px, double, c, s);
	MRPT_LOAD_CONFIG_VAR(huber_k, double, c, s);
	MRPT_LOAD_CONFIG_VAR(kf_translation, double, c, s);
	MRPT_LOAD_CONFIG_VAR(kf_rotation_deg, double, c, s);
	MRPT_LOAD_CONFIG_VAR(kf_min_tracked_fraction, double, c, s);
	MRPT_LOAD_CONFIG_VAR(kf_min_inliers, int, c, s);
	MRPT_LOAD_CONFIG_VAR(max_step_translation, double, c, s);
	MRPT_LOAD_CONFIG_VAR(max_step_rotation_deg, double, c, s);
	MRPT_LOAD_CONFIG_VAR(max_lost_frames, int, c, s);
	MRPT_LOAD_CONFIG_VAR(constant_velocity, bool, c, s);
	MRPT_LOAD_CONFIG_VAR(two_view_ba, bool, c, s);
	MRPT_LOAD_CONFIG_VAR(ransac_prediction, bool, c, s);
	MRPT_LOAD_CONFIG_VAR(ransac_prior_sigma_m, double, c, s);
	try
	{
		validate();
	}
	catch (const std::exception& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

void TStereoVOOptions::dumpToTextStream(std::ostream& o) const
{
	o << "search_radius_px = " << search_radius_px << "   ; BRIEF window [px]\n"
	  << "search_radius_lost_px = " << search_radius_lost_px << "   ; window after a failure [px]\n"
	  << "max_hamming = " << max_hamming << "   ; [bits]\n"
	  << "match_ratio = " << match_ratio << "   ; best/second best distance\n"
	  << "refine_min_zncc = " << refine_min_zncc << "   ; patch refinement correlation\n"
	  << "refine_radius = " << refine_radius << "   ; [px]\n"
	  << "refine_iterations = " << refine_iterations << "   ; Gauss-Newton steps, 0 = parabola only\n"
	  << "min_stereo = " << min_stereo << "\n"
	  << "min_matches = " << min_matches << "\n"
	  << "min_inliers = " << min_inliers << "\n"
	  << "near_min_disparity = " << near_min_disparity << "   ; far landmarks left out of the solve when enough near ones, 0 = off [px]\n"
	  << "near_min_matches = " << near_min_matches << "\n"
	  << "ransac_threshold_px = " << ransac_threshold_px << "   ; [px]\n"
	  << "ransac_iterations = " << ransac_iterations << "\n"
	  << "sigma_px = " << sigma_px << "   ; [px]\n"
	  << "huber_k = " << huber_k << "   ; [sigmas]\n"
	  << "kf_translation = " << kf_translation << "   ; [m]\n"
	  << "kf_rotation_deg = " << kf_rotation_deg << "   ; [deg]\n"
	  << "kf_min_tracked_fraction = " << kf_min_tracked_fraction << "\n"
	  << "kf_min_inliers = " << kf_min_inliers << "\n"
	  << "max_step_translation = " << max_step_translation << "   ; [m]\n"
	  << "max_step_rotation_deg = " << max_step_rotation_deg << "   ; [deg]\n"
	  << "max_lost_frames = " << max_lost_frames << "\n"
	  << "constant_velocity = " << (constant_velocity ? "true" : "false") << "\n"
	  << "two_view_ba = " << (two_view_ba ? "true" : "false") << "   ; solve by two-view bundle adjustment\n"
	  << "ransac_prediction = " << (ransac_prediction ? "true" : "false") << "   ; the prediction is a RANSAC hypothesis\n"
	  << "ransac_prior_sigma_m = " << ransac_prior_sigma_m << "   ; preference for hypotheses near the prediction, 0 = off [m]\n";
}

void TStereoVOOptions::validate() const
{
	auto bad = [](const std::string& w) { throw std::invalid_argument("option " + w); };
	if (!(search_radius_px > 0) || search_radius_lost_px < search_radius_px)
		bad("search_radius_px must be > 0 and <= search_radius_lost_px");
	if (max_hamming < 1 || max_hamming > 256) bad("max_hamming must be in [1,256]");
	if (!(match_ratio > 0 && match_ratio <= 1)) bad("match_ratio must be in (0,1]");
	if (refine_radius < 0 || refine_radius > 4) bad("refine_radius must be in [0,4]");
	if (refine_iterations < 0 || refine_iterations > 20) bad("refine_iterations must be in [0,20]");
	if (min_inliers < 3 || min_matches < min_inliers) bad("need 3 <= min_inliers <= min_matches");
	if (!(near_min_disparity >= 0) || near_min_matches < min_matches)
		bad("near_min_disparity must be >= 0 and near_min_matches >= min_matches");
	if (!(ransac_threshold_px > 0) || ransac_iterations < 1) bad("ransac_threshold_px/iterations must be > 0");
	if (!(sigma_px > 0) || !(huber_k > 0)) bad("sigma_px and huber_k must be > 0");
	if (!(kf_translation > 0) || !(kf_rotation_deg > 0)) bad("kf_translation/kf_rotation_deg must be > 0");
	if (!(max_step_translation > 0) || !(max_step_rotation_deg > 0)) bad("max_step_* must be > 0");
	if (max_lost_frames < 0) bad("max_lost_frames must be >= 0");
	if (!(ransac_prior_sigma_m >= 0)) bad("ransac_prior_sigma_m must be >= 0 (0 = off)");
}

}  // namespace shadyloc::vo
