/* ShadyLoc simulator — options. */
#include <shadyloc/sim/SimOptions.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/system/string_utils.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>

namespace shadyloc::sim
{
namespace
{
/** Strict reading of one section: values must parse completely, and keys the
 * section does not know are reported (a typo must not fall back silently). */
class StrictSection
{
   public:
	StrictSection(const mrpt::config::CConfigFileBase& c, const std::string& s) : m_c(c), m_s(s) {}

	/** The value of key without an inline comment (from ';' or '#'), trimmed. */
	std::string raw(const char* key) const
	{
		std::string v = m_c.read_string(m_s, key, "");
		const size_t cut = v.find_first_of(";#");
		if (cut != std::string::npos) v.resize(cut);
		return mrpt::system::trim(v);
	}

	void num(const char* key, double& v)
	{
		m_known.insert(key);
		if (!m_c.keyExists(m_s, key)) return;
		const std::string txt = raw(key);
		size_t used = 0;
		try
		{
			v = std::stod(txt, &used);
		}
		catch (...)
		{
			used = 0;
		}
		if (used == 0 || used != txt.size() || !std::isfinite(v)) bad(key, txt, "a number");
	}
	void integer(const char* key, int& v)
	{
		double d = v;
		num(key, d);
		if (d != std::floor(d) || std::abs(d) > 1e9)
			bad(key, raw(key), "an integer");
		v = static_cast<int>(d);
	}
	void seed(const char* key, uint32_t& v)
	{
		double d = v;
		num(key, d);
		if (d != std::floor(d) || d < 0 || d > 4294967295.0)
			bad(key, raw(key), "an integer in [0, 2^32)");
		v = static_cast<uint32_t>(d);
	}
	void flag(const char* key, bool& v)
	{
		m_known.insert(key);
		if (!m_c.keyExists(m_s, key)) return;
		const std::string t = mrpt::system::lowerCase(raw(key));
		if (t == "true" || t == "1" || t == "yes")
			v = true;
		else if (t == "false" || t == "0" || t == "no")
			v = false;
		else
			bad(key, t, "true or false");
	}
	void text(const char* key, std::string& v)
	{
		m_known.insert(key);
		if (m_c.keyExists(m_s, key)) v = raw(key);
	}
	/** Throws if the section holds a key no reader asked for. */
	void rejectUnknown() const
	{
		std::vector<std::string> keys;
		m_c.getAllKeys(m_s, keys);
		for (const auto& k : keys)
			if (!m_known.count(k))
			{
				std::string list;
				for (const auto& kk : m_known) list += " " + kk;
				throw std::invalid_argument(
					"[" + m_s + "] unknown option '" + k + "' (known:" + list + ")");
			}
	}

   private:
	[[noreturn]] void bad(const char* key, const std::string& txt, const char* want) const
	{
		throw std::invalid_argument(
			"[" + m_s + "] " + key + " = '" + txt + "': expected " + want);
	}
	const mrpt::config::CConfigFileBase& m_c;
	std::string m_s;
	std::set<std::string> m_known;
};

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
	StrictSection r(c, s);
	r.integer("width", width);
	r.integer("height", height);
	r.num("hfov_deg", hfov_deg);
	r.num("baseline_m", baseline_m);
	r.num("height_m", height_m);
	r.num("pitch_deg", pitch_deg);
	r.num("fps", fps);
	r.num("lambda_min_nm", grid.min_nm);
	r.num("lambda_max_nm", grid.max_nm);
	r.num("lambda_step_nm", grid.step_nm);
	r.num("peak_wavelength_blue_nm", spectral.peak_nm[0]);
	r.num("peak_wavelength_green_nm", spectral.peak_nm[1]);
	r.num("peak_wavelength_red_nm", spectral.peak_nm[2]);
	r.num("sensitivity_sigma_nm", spectral.sigma_nm);
	r.num("white_balance_K", spectral.white_balance_K);
	r.num("exposure_percentile", exposure_percentile);
	r.num("exposure_target", exposure_target);
	r.num("exposure_smoothing", exposure_smoothing);
	r.num("exposure_roi_top", exposure_roi_top);
	r.flag("noise", noise);
	r.num("full_well_e", full_well_e);
	r.num("read_noise_e", read_noise_e);
	r.rejectUnknown();
	validate();
}

void TSimCameraOptions::validate() const
{
	const std::string s = "sim.camera";
	require(width >= 16 && width <= 8192, s, "width must be in [16, 8192] px");
	require(height >= 16 && height <= 8192, s, "height must be in [16, 8192] px");
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
	o << "[sim.camera]\n"
	  << "width = " << width << "  ; px\nheight = " << height << "  ; px\n"
	  << "hfov_deg = " << hfov_deg << "  ; focal length " << focalPx() << " px\n"
	  << "baseline_m = " << baseline_m << "\nheight_m = " << height_m << "\npitch_deg = " << pitch_deg
	  << "\nfps = " << fps << "\nlambda_min_nm = " << grid.min_nm << "\nlambda_max_nm = " << grid.max_nm
	  << "\nlambda_step_nm = " << grid.step_nm
	  << "\npeak_wavelength_blue_nm = " << spectral.peak_nm[0]
	  << "\npeak_wavelength_green_nm = " << spectral.peak_nm[1]
	  << "\npeak_wavelength_red_nm = " << spectral.peak_nm[2]
	  << "\nsensitivity_sigma_nm = " << spectral.sigma_nm
	  << "\nwhite_balance_K = " << spectral.white_balance_K
	  << "\nexposure_percentile = " << exposure_percentile << "\nexposure_target = " << exposure_target
	  << "\nexposure_roi_top = " << exposure_roi_top << "\nexposure_smoothing = " << exposure_smoothing << "\nnoise = " << (noise ? "true" : "false")
	  << "\nfull_well_e = " << full_well_e << "\nread_noise_e = " << read_noise_e << "\n";
}

// ---------------------------------------------------------------- scene
void TSimSceneOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	StrictSection r(c, s);
	r.seed("seed", seed);
	r.num("route_length_m", route_length_m);
	r.num("route_amplitude_m", route_amplitude_m);
	r.num("road_half_width_m", road_half_width_m);
	r.num("sidewalk_width_m", sidewalk_width_m);
	r.num("lane_offset_m", lane_offset_m);
	r.num("trees_end_m", trees_end_m);
	r.num("buildings_end_m", buildings_end_m);
	r.num("tree_spacing_m", tree_spacing_m);
	r.num("canopy_gap_fraction", canopy_gap_fraction);
	r.num("leaf_scale_m", leaf_scale_m);
	r.num("canopy_wind_m", canopy_wind_m);
	r.num("texture_contrast", texture_contrast);
	r.num("texture_chroma", texture_chroma);
	r.num("max_distance_m", max_distance_m);
	std::string m;
	r.text("markers", m);
	r.rejectUnknown();
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
	o << "[sim.scene]\nseed = " << seed << "\nroute_length_m = " << route_length_m
	  << "\nroute_amplitude_m = " << route_amplitude_m << "\nroad_half_width_m = " << road_half_width_m
	  << "\nsidewalk_width_m = " << sidewalk_width_m << "\nlane_offset_m = " << lane_offset_m
	  << "\ntrees_end_m = " << trees_end_m << "\nbuildings_end_m = " << buildings_end_m
	  << "\ntree_spacing_m = " << tree_spacing_m << "\ncanopy_gap_fraction = " << canopy_gap_fraction
	  << "\nleaf_scale_m = " << leaf_scale_m << "\ncanopy_wind_m = " << canopy_wind_m
	  << "\ntexture_contrast = " << texture_contrast << "\ntexture_chroma = " << texture_chroma
	  << "\nmax_distance_m = " << max_distance_m << "\nmarkers = ";
	for (size_t i = 0; i < markers.size(); i++)
		o << (i ? ", " : "") << markers[i][0] << " " << markers[i][1] << " " << markers[i][2] << " "
		  << markers[i][3];
	o << "\n";
}

// ---------------------------------------------------------------- traversal
void TTraversal::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	StrictSection r(c, s);
	r.num("sun_azimuth_deg", sun_azimuth_deg);
	r.num("sun_elevation_deg", sun_elevation_deg);
	r.num("sun_temperature_K", sun_temperature_K);
	r.num("sky_temperature_K", sky_temperature_K);
	r.num("sun_irradiance", sun_irradiance);
	r.num("sky_irradiance", sky_irradiance);
	r.flag("overcast", overcast);
	r.num("lateral_offset_m", lateral_offset_m);
	r.num("weave_amplitude_m", weave_amplitude_m);
	r.num("speed_mps", speed_mps);
	r.num("speed_variation", speed_variation);
	r.num("start_s_m", start_s_m);
	r.integer("frames", frames);
	r.seed("wind_seed", wind_seed);
	r.seed("noise_seed", noise_seed);
	r.num("start_time", start_time);
	r.rejectUnknown();
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
	require(frames >= 1 && frames <= 1000000, s, "frames must be in [1, 1e6]");
	require(start_time >= 0, s, "start_time must be >= 0 s");
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
	o << "[traversal." << name << "]\nsun_azimuth_deg = " << sun_azimuth_deg
	  << "\nsun_elevation_deg = " << sun_elevation_deg << "\nsun_temperature_K = " << sun_temperature_K
	  << "\nsky_temperature_K = " << sky_temperature_K << "\nsun_irradiance = " << sun_irradiance
	  << "  ; effective " << effectiveSunIrradiance() << "\nsky_irradiance = " << sky_irradiance
	  << "\novercast = " << (overcast ? "true" : "false") << "\nlateral_offset_m = " << lateral_offset_m
	  << "\nweave_amplitude_m = " << weave_amplitude_m << "\nspeed_mps = " << speed_mps
	  << "\nspeed_variation = " << speed_variation << "\nstart_s_m = " << start_s_m
	  << "\nframes = " << frames << "\nwind_seed = " << wind_seed << "\nnoise_seed = " << noise_seed
	  << "\nstart_time = " << std::fixed << std::setprecision(3) << start_time << std::defaultfloat
	  << "\n";
}

// ---------------------------------------------------------------- all
void TSimOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	StrictSection r(c, s);
	std::string list;
	r.text("traversals", list);
	r.rejectUnknown();
	camera.loadFromConfigFile(c, s + ".camera");
	scene.loadFromConfigFile(c, s + ".scene");
	std::vector<std::string> names;
	mrpt::system::tokenize(list, " ,\t", names);
	if (names.empty()) throw std::invalid_argument("[" + s + "] traversals: no traversal listed");
	std::vector<std::string> sections;
	c.getAllSections(sections);
	traversals.clear();
	for (const auto& n : names)
	{
		const std::string sect = "traversal." + n;
		if (std::find(sections.begin(), sections.end(), sect) == sections.end())
			throw std::invalid_argument("[" + s + "] traversals: '" + n + "' has no section [" + sect + "]");
		TTraversal t;
		t.name = n;
		t.loadFromConfigFile(c, sect);
		traversals.push_back(t);
	}
}

void TSimOptions::dumpToTextStream(std::ostream& o) const
{
	o << "[sim]\ntraversals =";
	for (const auto& t : traversals) o << " " << t.name;
	o << "\n\n";
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
		throw SimOptionsError("'" + path + "': " + e.what());
	}
	return o;
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
