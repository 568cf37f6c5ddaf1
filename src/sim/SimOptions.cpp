/* ShadyLoc simulator — options. */
#include <shadyloc/sim/SimOptions.h>

#include <shadyloc/core/Options.h>

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
using core::Range;
using core::SettingsSection;
using core::SettingsWriter;

void require(bool ok, const std::string& section, const std::string& what)
{
	if (!ok) throw std::invalid_argument("[" + section + "] " + what);
}

/** Runs check, its std::invalid_argument ("key: why") naming the section. */
template <typename F>
void inSection(const std::string& section, F&& check)
{
	try
	{
		check();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + section + "] " + e.what());
	}
}

/** The keys of o from section s; then o.validate(), whose errors name the
 * section (the file is added by TSimOptions::FromFile). */
template <typename T>
void loadSection(T& o, const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	SettingsSection r(c, s);
	core::readKeys(r, o);
	r.finish();
	o.validate();
}

/** "[section]" and the keys of o. */
template <typename T>
void dumpSection(const T& o, const std::string& section, std::ostream& out)
{
	SettingsWriter w(out);
	w.section(section);
	core::writeKeys(w, o);
}
}  // namespace

// ---------------------------------------------------------------- camera
double TSimCameraOptions::focalPx() const
{
	return 0.5 * width / std::tan(0.5 * hfov_deg * M_PI / 180.0);
}

void TSimCameraOptions::keys(core::KeyVisitor& v)
{
	v.renamed({{"width", "width_px"}, {"height", "height_px"}});
	v("width_px", width, "", Range::closed(16, 8192), "");
	v("height_px", height, "", Range::closed(16, 8192), "");
	const double f = focalPx();
	v("hfov_deg", hfov_deg, "", Range::open(5, 170),
	  std::isfinite(f) ? "focal length " + core::formatSetting(f) + " px" : std::string());
	v("baseline_m", baseline_m, "", Range::open(0, 5), "");
	v("height_m", height_m, "", Range::open(0.1, 20), "");
	v("pitch_deg", pitch_deg, "", Range::open(-45, 45), "");
	v("fps", fps, "", Range::openClosed(0, 1000), "");
	// The spectral model checks its own (WavelengthGrid, CameraSpectralModel::validate).
	v("lambda_min_nm", grid.min_nm, "", Range::any(), "");
	v("lambda_max_nm", grid.max_nm, "", Range::any(), "");
	v("lambda_step_nm", grid.step_nm, "", Range::any(), "");
	v("peak_wavelength_blue_nm", spectral.peak_nm[0], "", Range::any(), "");
	v("peak_wavelength_green_nm", spectral.peak_nm[1], "", Range::any(), "");
	v("peak_wavelength_red_nm", spectral.peak_nm[2], "", Range::any(), "");
	v("sensitivity_sigma_nm", spectral.sigma_nm, "", Range::any(), "");
	v("white_balance_K", spectral.white_balance_K, "", Range::any(), "");
	v("exposure_percentile", exposure_percentile, "", Range::openClosed(0, 1), "");
	v("exposure_target", exposure_target, "", Range::openClosed(1, 255), "");
	v("exposure_roi_top", exposure_roi_top, "", Range::closedOpen(0, 0.9), "");
	v("exposure_smoothing", exposure_smoothing, "", Range::closedOpen(0, 1), "");
	v("noise", noise, "", Range::any(), "");
	v("full_well_e", full_well_e, "", Range::above(10), "");
	v("read_noise_e", read_noise_e, "", Range::atLeast(0), "");
}

void TSimCameraOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	loadSection(*this, c, s);
}

void TSimCameraOptions::validate() const
{
	inSection("sim.camera", [&] {
		core::checkKeys(*this);
		grid.validate();
		spectral.validate();
	});
}

void TSimCameraOptions::dumpToTextStream(std::ostream& o) const { dumpSection(*this, "sim.camera", o); }

// ---------------------------------------------------------------- scene
std::string TSimSceneOptions::markersText(const std::vector<std::array<double, 4>>& markers)
{
	std::string m;
	for (size_t i = 0; i < markers.size(); i++)
		for (size_t k = 0; k < 4; k++)
			m += (k ? " " : (i ? ", " : "")) + core::formatSetting(markers[i][k]);
	return m;
}

std::vector<std::array<double, 4>> TSimSceneOptions::parseMarkers(const std::string& text)
{
	std::vector<std::array<double, 4>> markers;
	std::vector<std::string> items;
	mrpt::system::tokenize(text, ",", items);
	for (const auto& it : items)
	{
		std::istringstream is(it);
		std::array<double, 4> v{};
		std::string extra;
		if (!(is >> v[0] >> v[1] >> v[2] >> v[3]) || (is >> extra))
			throw std::invalid_argument("'" + it + "': expected 'x y z radius'");
		markers.push_back(v);
	}
	return markers;
}

void TSimSceneOptions::keys(core::KeyVisitor& v)
{
	v("seed", seed, "", Range::any(), "");
	v("route_length_m", route_length_m, "", Range::closed(20, 20000), "");
	v("route_amplitude_m", route_amplitude_m, "", Range::any(), "");
	v("road_half_width_m", road_half_width_m, "", Range::open(1, 20), "");
	v("sidewalk_width_m", sidewalk_width_m, "", Range::closedOpen(0, 20), "");
	v("lane_offset_m", lane_offset_m, "", Range::any(), "");
	v("trees_end_m", trees_end_m, "", Range::atLeast(0), "");
	v("buildings_end_m", buildings_end_m, "", Range::any(), "");
	v("tree_spacing_m", tree_spacing_m, "", Range::atLeast(2), "");
	v("canopy_gap_fraction", canopy_gap_fraction, "", Range::closed(0, 1), "");
	v("leaf_scale_m", leaf_scale_m, "", Range::open(0.05, 10), "");
	v("canopy_wind_m", canopy_wind_m, "", Range::closedOpen(0, 10), "");
	v("texture_contrast", texture_contrast, "", Range::closed(0, 3), "");
	v("texture_chroma", texture_chroma, "", Range::closed(0, 3), "");
	v("max_distance_m", max_distance_m, "", Range::closed(10, 5000), "");
	v.text("markers", markers, markersText, parseMarkers, "x y z radius [m], ...");
}

void TSimSceneOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	loadSection(*this, c, s);
}

void TSimSceneOptions::validate() const
{
	const std::string s = "sim.scene";
	inSection(s, [&] { core::checkKeys(*this); });
	require(std::abs(route_amplitude_m) <= route_length_m / 8, s,
			"route_amplitude_m must be at most route_length_m/8 (a gentle curve)");
	require(std::abs(lane_offset_m) < road_half_width_m, s, "lane_offset_m must lie on the road");
	require(buildings_end_m >= trees_end_m, s, "need 0 <= trees_end_m <= buildings_end_m");
	for (const auto& m : markers) require(m[3] > 0, s, "markers: radius must be > 0");
}

void TSimSceneOptions::dumpToTextStream(std::ostream& o) const { dumpSection(*this, "sim.scene", o); }

// ---------------------------------------------------------------- traversal
void TTraversal::keys(core::KeyVisitor& v)
{
	v.renamed({{"start_time", "start_time_s"}});
	v("sun_azimuth_deg", sun_azimuth_deg, "", Range::any(), "");
	v("sun_elevation_deg", sun_elevation_deg, "", Range::openClosed(-90, 90), "");
	v("sun_temperature_K", sun_temperature_K, "", Range::open(1000, 1e5), "");
	v("sky_temperature_K", sky_temperature_K, "", Range::open(1000, 1e5), "");
	const double effective = effectiveSunIrradiance();
	v("sun_irradiance", sun_irradiance, "", Range::below(100),
	  std::isfinite(effective) ? "< 0: from the elevation; effective " + core::formatSetting(effective) : std::string());
	v("sky_irradiance", sky_irradiance, "", Range::open(0, 100), "");
	v("overcast", overcast, "", Range::any(), "");
	v("lateral_offset_m", lateral_offset_m, "", Range::any(), "");
	v("weave_amplitude_m", weave_amplitude_m, "", Range::open(-5, 5), "");
	v("speed_mps", speed_mps, "", Range::open(0, 100), "");
	v("speed_variation", speed_variation, "", Range::closedOpen(0, 1), "");
	v("start_s_m", start_s_m, "", Range::closed(-1e6, 1e6), "");
	// A count or an end: the dump writes the one in use.
	v("end_s_m", end_s_m, "", Range::any(), "the last frame is the first at or past this route position",
	  endsByDistance());
	v("frames", frames, "", Range::closed(0, 1e6), "", !endsByDistance());
	v("wind_seed", wind_seed, "", Range::any(), "");
	v("noise_seed", noise_seed, "", Range::any(), "");
	v("start_time_s", start_time, "", Range::atLeast(0), "");
}

void TTraversal::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	SettingsSection r(c, s);
	// A count or an end, never both: which one wins would be a guess.
	if (r.has("frames") && r.has("end_s_m"))
		r.fail("end_s_m", "give either frames (a count) or end_s_m (a route position), not both");
	const bool byEnd = r.has("end_s_m");
	core::readKeys(r, *this);
	if (byEnd)
		frames = 0;
	else if (r.has("frames") && frames == 0)
		r.fail("frames", "must be >= 1 (or give end_s_m instead)");
	r.finish();
	validate();
}

void TTraversal::validate() const
{
	const std::string s = "traversal." + name;
	inSection(s, [&] { core::checkKeys(*this); });
	if (endsByDistance())
		require(end_s_m > start_s_m, s, "end_s_m must be > start_s_m");
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

void TTraversal::dumpToTextStream(std::ostream& o) const { dumpSection(*this, "traversal." + name, o); }

// ---------------------------------------------------------------- all
void TSimOptions::keys(core::KeyVisitor& v)
{
	const auto names = [](const std::vector<TTraversal>& ts) {
		std::string n;
		for (const auto& t : ts) n += (n.empty() ? "" : " ") + t.name;
		return n;
	};
	// Only the names: each traversal is read from its own section.
	const auto parse = [](const std::string& text) {
		std::vector<std::string> names;
		mrpt::system::tokenize(text, " ,\t", names);
		std::vector<TTraversal> ts(names.size());
		for (size_t i = 0; i < names.size(); i++) ts[i].name = names[i];
		return ts;
	};
	v.text("traversals", traversals, names, parse, "");
}

void TSimOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	SettingsSection r(c, s);
	traversals.clear();
	core::readKeys(r, *this);
	r.finish();
	if (traversals.empty()) r.fail("traversals", "no traversal listed");
	// Every section must be one of these: a [traversal.x] not listed would never be rendered.
	std::vector<std::string> known = {s, s + ".camera", s + ".scene"};
	for (const auto& t : traversals) known.push_back("traversal." + t.name);
	core::checkSections(c, known, "simulator config ([traversal.<name>] sections must be listed in [" + s + "] traversals)");
	camera.loadFromConfigFile(c, s + ".camera");
	scene.loadFromConfigFile(c, s + ".scene");
	std::vector<std::string> sections;
	c.getAllSections(sections);
	for (auto& t : traversals)
	{
		const std::string sect = "traversal." + t.name;
		if (std::find(sections.begin(), sections.end(), sect) == sections.end())
			r.fail("traversals", "'" + t.name + "' has no section [" + sect + "]");
		t.loadFromConfigFile(c, sect);
		validateTraversal(t);
	}
}

void TSimOptions::dumpToTextStream(std::ostream& o) const
{
	dumpSection(*this, "sim", o);
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
