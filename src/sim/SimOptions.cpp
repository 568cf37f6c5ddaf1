/* ShadyLoc simulator — options. */
#include <shadyloc/sim/SimOptions.h>

#include <shadyloc/core/Settings.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/system/string_utils.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <sstream>

namespace shadyloc::sim
{
namespace
{
using core::SettingsSection;
using core::SettingsWriter;

void require(bool ok, const std::string& section, const std::string& what)
{
	if (!ok) throw std::invalid_argument("[" + section + "] " + what);
}
}  // namespace

// ---------------------------------------------------------------- camera
double TSimCameraOptions::focalPx() const
{
	return 0.5 * width / std::tan(0.5 * hfov_deg * M_PI / 180.0);
}

void TSimCameraOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	SettingsSection r(c, s);
	r.renamed({{"width", "width_px"}, {"height", "height_px"}});
	r.read("width_px", width);
	r.read("height_px", height);
	r.read("hfov_deg", hfov_deg);
	r.read("baseline_m", baseline_m);
	r.read("height_m", height_m);
	r.read("pitch_deg", pitch_deg);
	r.read("fps", fps);
	r.read("lambda_min_nm", grid.min_nm);
	r.read("lambda_max_nm", grid.max_nm);
	r.read("lambda_step_nm", grid.step_nm);
	r.read("peak_wavelength_blue_nm", spectral.peak_nm[0]);
	r.read("peak_wavelength_green_nm", spectral.peak_nm[1]);
	r.read("peak_wavelength_red_nm", spectral.peak_nm[2]);
	r.read("sensitivity_sigma_nm", spectral.sigma_nm);
	r.read("white_balance_K", spectral.white_balance_K);
	r.read("exposure_percentile", exposure_percentile);
	r.read("exposure_target", exposure_target);
	r.read("exposure_smoothing", exposure_smoothing);
	r.read("exposure_roi_top", exposure_roi_top);
	r.read("noise", noise);
	r.read("full_well_e", full_well_e);
	r.read("read_noise_e", read_noise_e);
	r.finish();
	validate();
}

void TSimCameraOptions::validate() const
{
	const std::string s = "sim.camera";
	require(width >= 16 && width <= 8192, s, "width_px must be in [16, 8192]");
	require(height >= 16 && height <= 8192, s, "height_px must be in [16, 8192]");
	require(hfov_deg > 5 && hfov_deg < 170, s, "hfov_deg must be in (5, 170) deg");
	require(baseline_m > 0 && baseline_m < 5, s, "baseline_m must be in (0, 5) m");
	require(height_m > 0.1 && height_m < 20, s, "height_m must be in (0.1, 20) m");
	require(std::abs(pitch_deg) < 45, s, "pitch_deg must be in (-45, 45) deg");
	require(fps > 0 && fps <= 1000, s, "fps must be in (0, 1000] Hz");
	require(exposure_percentile > 0 && exposure_percentile <= 1, s, "exposure_percentile must be in (0, 1]");
	require(exposure_target > 1 && exposure_target <= 255, s, "exposure_target must be in (1, 255]");
	require(exposure_roi_top >= 0 && exposure_roi_top < 0.9, s, "exposure_roi_top must be in [0, 0.9)");
	require(exposure_smoothing >= 0 && exposure_smoothing < 1, s, "exposure_smoothing must be in [0, 1)");
	require(full_well_e > 10, s, "full_well_e must be > 10 electrons");
	require(read_noise_e >= 0, s, "read_noise_e must be >= 0 electrons");
	try
	{
		grid.validate();
		spectral.validate();
	}
	catch (const std::exception& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

void TSimCameraOptions::dumpToTextStream(std::ostream& o) const
{
	SettingsWriter w(o);
	w.section("sim.camera");
	w.value("width_px", width);
	w.value("height_px", height);
	w.value("hfov_deg", hfov_deg, "focal length " + core::formatSetting(focalPx()) + " px");
	w.value("baseline_m", baseline_m);
	w.value("height_m", height_m);
	w.value("pitch_deg", pitch_deg);
	w.value("fps", fps);
	w.value("lambda_min_nm", grid.min_nm);
	w.value("lambda_max_nm", grid.max_nm);
	w.value("lambda_step_nm", grid.step_nm);
	w.value("peak_wavelength_blue_nm", spectral.peak_nm[0]);
	w.value("peak_wavelength_green_nm", spectral.peak_nm[1]);
	w.value("peak_wavelength_red_nm", spectral.peak_nm[2]);
	w.value("sensitivity_sigma_nm", spectral.sigma_nm);
	w.value("white_balance_K", spectral.white_balance_K);
	w.value("exposure_percentile", exposure_percentile);
	w.value("exposure_target", exposure_target);
	w.value("exposure_roi_top", exposure_roi_top);
	w.value("exposure_smoothing", exposure_smoothing);
	w.value("noise", noise);
	w.value("full_well_e", full_well_e);
	w.value("read_noise_e", read_noise_e);
}

// ---------------------------------------------------------------- scene
void TSimSceneOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	SettingsSection r(c, s);
	r.read("seed", seed);
	r.read("route_length_m", route_length_m);
	r.read("route_amplitude_m", route_amplitude_m);
	r.read("road_half_width_m", road_half_width_m);
	r.read("sidewalk_width_m", sidewalk_width_m);
	r.read("lane_offset_m", lane_offset_m);
	r.read("trees_end_m", trees_end_m);
	r.read("buildings_end_m", buildings_end_m);
	r.read("tree_spacing_m", tree_spacing_m);
	r.read("canopy_gap_fraction", canopy_gap_fraction);
	r.read("leaf_scale_m", leaf_scale_m);
	r.read("canopy_wind_m", canopy_wind_m);
	r.read("texture_contrast", texture_contrast);
	r.read("texture_chroma", texture_chroma);
	r.read("max_distance_m", max_distance_m);
	std::string m;
	r.read("markers", m);
	r.finish();
	markers.clear();
	std::vector<std::string> items;
	mrpt::system::tokenize(m, ",", items);
	for (const auto& it : items)
	{
		std::istringstream is(it);
		std::array<double, 4> v{};
		std::string extra;
		if (!(is >> v[0] >> v[1] >> v[2] >> v[3]) || (is >> extra))
			throw std::invalid_argument("[" + s + "] markers: '" + it + "': expected 'x y z radius'");
		markers.push_back(v);
	}
	validate();
}

void TSimSceneOptions::validate() const
{
	const std::string s = "sim.scene";
	require(route_length_m >= 20 && route_length_m <= 20000, s, "route_length_m must be in [20, 20000] m");
	require(std::abs(route_amplitude_m) <= route_length_m / 8, s,
			"route_amplitude_m must be at most route_length_m/8 (a gentle curve)");
	require(road_half_width_m > 1 && road_half_width_m < 20, s, "road_half_width_m must be in (1, 20) m");
	require(sidewalk_width_m >= 0 && sidewalk_width_m < 20, s, "sidewalk_width_m must be in [0, 20) m");
	require(std::abs(lane_offset_m) < road_half_width_m, s, "lane_offset_m must lie on the road");
	require(trees_end_m >= 0 && buildings_end_m >= trees_end_m, s,
			"need 0 <= trees_end_m <= buildings_end_m");
	require(tree_spacing_m >= 2, s, "tree_spacing_m must be >= 2 m");
	require(canopy_gap_fraction >= 0 && canopy_gap_fraction <= 1, s, "canopy_gap_fraction must be in [0, 1]");
	require(leaf_scale_m > 0.05 && leaf_scale_m < 10, s, "leaf_scale_m must be in (0.05, 10) m");
	require(canopy_wind_m >= 0 && canopy_wind_m < 10, s, "canopy_wind_m must be in [0, 10) m");
	require(texture_contrast >= 0 && texture_contrast <= 3, s, "texture_contrast must be in [0, 3]");
	require(texture_chroma >= 0 && texture_chroma <= 3, s, "texture_chroma must be in [0, 3]");
	require(max_distance_m >= 10 && max_distance_m <= 5000, s, "max_distance_m must be in [10, 5000] m");
	for (const auto& m : markers) require(m[3] > 0, s, "markers: radius must be > 0");
}

void TSimSceneOptions::dumpToTextStream(std::ostream& o) const
{
	SettingsWriter w(o);
	w.section("sim.scene");
	w.value("seed", seed);
	w.value("route_length_m", route_length_m);
	w.value("route_amplitude_m", route_amplitude_m);
	w.value("road_half_width_m", road_half_width_m);
	w.value("sidewalk_width_m", sidewalk_width_m);
	w.value("lane_offset_m", lane_offset_m);
	w.value("trees_end_m", trees_end_m);
	w.value("buildings_end_m", buildings_end_m);
	w.value("tree_spacing_m", tree_spacing_m);
	w.value("canopy_gap_fraction", canopy_gap_fraction);
	w.value("leaf_scale_m", leaf_scale_m);
	w.value("canopy_wind_m", canopy_wind_m);
	w.value("texture_contrast", texture_contrast);
	w.value("texture_chroma", texture_chroma);
	w.value("max_distance_m", max_distance_m);
	std::string m;
	for (size_t i = 0; i < markers.size(); i++)
		for (size_t k = 0; k < 4; k++)
			m += (k ? " " : (i ? ", " : "")) + core::formatSetting(markers[i][k]);
	w.value("markers", m, "x y z radius [m], ...");
}

// ---------------------------------------------------------------- traversal
void TTraversal::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	SettingsSection r(c, s);
	r.renamed({{"start_time", "start_time_s"}});
	r.read("sun_azimuth_deg", sun_azimuth_deg);
	r.read("sun_elevation_deg", sun_elevation_deg);
	r.read("sun_temperature_K", sun_temperature_K);
	r.read("sky_temperature_K", sky_temperature_K);
	r.read("sun_irradiance", sun_irradiance);
	r.read("sky_irradiance", sky_irradiance);
	r.read("overcast", overcast);
	r.read("lateral_offset_m", lateral_offset_m);
	r.read("weave_amplitude_m", weave_amplitude_m);
	r.read("speed_mps", speed_mps);
	r.read("speed_variation", speed_variation);
	r.read("start_s_m", start_s_m);
	// A count or an end, never both: which one wins would be a guess.
	if (r.has("frames") && r.has("end_s_m"))
		r.fail("end_s_m", "give either frames (a count) or end_s_m (a route position), not both");
	r.read("frames", frames);
	if (r.has("end_s_m"))
	{
		r.read("end_s_m", end_s_m);
		frames = 0;
	}
	else if (r.has("frames") && frames == 0)
		r.fail("frames", "must be >= 1 (or give end_s_m instead)");
	r.read("wind_seed", wind_seed);
	r.read("noise_seed", noise_seed);
	r.read("start_time_s", start_time);
	r.finish();
	validate();
}

void TTraversal::validate() const
{
	const std::string s = "traversal." + name;
	require(sun_elevation_deg > -90 && sun_elevation_deg <= 90, s, "sun_elevation_deg must be in (-90, 90]");
	require(sun_temperature_K > 1000 && sun_temperature_K < 1e5, s, "sun_temperature_K must be in (1000, 1e5) K");
	require(sky_temperature_K > 1000 && sky_temperature_K < 1e5, s, "sky_temperature_K must be in (1000, 1e5) K");
	require(sun_irradiance < 100, s, "sun_irradiance must be < 100 (relative; < 0 = automatic)");
	require(sky_irradiance > 0 && sky_irradiance < 100, s, "sky_irradiance must be in (0, 100)");
	require(std::abs(weave_amplitude_m) < 5, s, "weave_amplitude_m must be in (-5, 5) m");
	require(speed_mps > 0 && speed_mps < 100, s, "speed_mps must be in (0, 100) m/s");
	require(speed_variation >= 0 && speed_variation < 1, s, "speed_variation must be in [0, 1)");
	require(frames >= 0 && frames <= 1000000, s, "frames must be in [1, 1e6] (0: up to end_s_m)");
	require(std::isfinite(start_s_m) && std::abs(start_s_m) <= 1e6, s, "start_s_m must be in [-1e6, 1e6] m");
	if (endsByDistance())
		require(std::isfinite(end_s_m) && end_s_m > start_s_m, s, "end_s_m must be > start_s_m");
	require(start_time >= 0, s, "start_time_s must be >= 0");
}

double TTraversal::effectiveSunIrradiance() const
{
	if (overcast || sun_elevation_deg <= 0.5) return 0.0;
	if (sun_irradiance >= 0) return sun_irradiance;
	// Kasten & Young (1989) air mass; 0.3 = broadband optical depth of a clear sky.
	const double e = sun_elevation_deg;
	const double airmass = 1.0 / (std::sin(e * M_PI / 180.0) + 0.50572 * std::pow(e + 6.07995, -1.6364));
	return std::exp(-0.3 * airmass);
}

void TTraversal::dumpToTextStream(std::ostream& o) const
{
	SettingsWriter w(o);
	w.section("traversal." + name);
	w.value("sun_azimuth_deg", sun_azimuth_deg);
	w.value("sun_elevation_deg", sun_elevation_deg);
	w.value("sun_temperature_K", sun_temperature_K);
	w.value("sky_temperature_K", sky_temperature_K);
	w.value("sun_irradiance", sun_irradiance,
			"< 0: from the elevation; effective " + core::formatSetting(effectiveSunIrradiance()));
	w.value("sky_irradiance", sky_irradiance);
	w.value("overcast", overcast);
	w.value("lateral_offset_m", lateral_offset_m);
	w.value("weave_amplitude_m", weave_amplitude_m);
	w.value("speed_mps", speed_mps);
	w.value("speed_variation", speed_variation);
	w.value("start_s_m", start_s_m);
	if (endsByDistance())
		w.value("end_s_m", end_s_m, "the last frame is the first at or past this route position");
	else
		w.value("frames", frames);
	w.value("wind_seed", wind_seed);
	w.value("noise_seed", noise_seed);
	w.value("start_time_s", start_time);
}

// ---------------------------------------------------------------- all
void TSimOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	SettingsSection r(c, s);
	std::string list;
	r.read("traversals", list);
	r.finish();
	std::vector<std::string> names;
	mrpt::system::tokenize(list, " ,\t", names);
	if (names.empty()) r.fail("traversals", "no traversal listed");
	// Every section must be one of these: a [traversal.x] not listed would never be rendered.
	std::vector<std::string> known = {s, s + ".camera", s + ".scene"};
	for (const auto& n : names) known.push_back("traversal." + n);
	core::checkSections(c, known, "simulator config ([traversal.<name>] sections must be listed in [" + s + "] traversals)");
	camera.loadFromConfigFile(c, s + ".camera");
	scene.loadFromConfigFile(c, s + ".scene");
	std::vector<std::string> sections;
	c.getAllSections(sections);
	traversals.clear();
	for (const auto& n : names)
	{
		const std::string sect = "traversal." + n;
		if (std::find(sections.begin(), sections.end(), sect) == sections.end())
			r.fail("traversals", "'" + n + "' has no section [" + sect + "]");
		TTraversal t;
		t.name = n;
		t.loadFromConfigFile(c, sect);
		validateTraversal(t);
		traversals.push_back(t);
	}
}

void TSimOptions::dumpToTextStream(std::ostream& o) const
{
	std::string names;
	for (const auto& t : traversals) names += (names.empty() ? "" : " ") + t.name;
	SettingsWriter w(o);
	w.section("sim");
	w.value("traversals", names);
	o << "\n";
	camera.dumpToTextStream(o);
	o << "\n";
	scene.dumpToTextStream(o);
	for (const auto& t : traversals)
	{
		o << "\n";
		t.dumpToTextStream(o);
	}
}

TSimOptions TSimOptions::FromFile(const std::string& path)
{
	if (!std::filesystem::is_regular_file(path))
		throw SimOptionsError("'" + path + "': simulator config file not found");
	TSimOptions o;
	try
	{
		mrpt::config::CConfigFile cfg(path);
		o.loadFromConfigFile(cfg, "sim");
	}
	catch (const std::exception& e)
	{
		throw SimOptionsError(core::withSource(path, e.what()));
	}
	return o;
}

void TSimOptions::validateTraversal(const TTraversal& t) const
{
	t.validate();
	if (t.endsByDistance() && t.end_s_m > scene.route_length_m + TSimSceneOptions::kEndMargin_m)
		throw std::invalid_argument(
			"[traversal." + t.name + "] end_s_m = " + core::formatSetting(t.end_s_m) +
			" lies past the end of the scene (at most " + core::formatSetting(TSimSceneOptions::kEndMargin_m) +
			" m past [sim.scene] route_length_m = " + core::formatSetting(scene.route_length_m) + ")");
}

const TTraversal& TSimOptions::traversal(const std::string& name) const
{
	for (const auto& t : traversals)
		if (t.name == name) return t;
	std::string known;
	for (const auto& t : traversals) known += " " + t.name;
	throw SimOptionsError("unknown traversal '" + name + "' (known:" + known + ")");
}

}  // namespace shadyloc::sim
