/* ShadyLoc simulator — options, loaded from an MRPT .ini file (config/sim.ini).
 *
 * Sections: [sim] (list of traversals), [sim.camera], [sim.scene] and one
 * [traversal.<name>] per traversal. Unknown keys are errors (a typo must not
 * silently fall back to a default), as are values out of range; every error
 * names the file, section and key.
 */
#pragma once

#include <shadyloc/sim/Spectral.h>

#include <mrpt/config/CLoadableOptions.h>

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::sim
{
/** Error in simulator options: what() names file, section and key. */
class SimOptionsError : public std::runtime_error
{
   public:
	using std::runtime_error::runtime_error;
};

/** The stereo rig and its sensor: geometry, spectral model, exposure, noise. */
struct TSimCameraOptions : public mrpt::config::CLoadableOptions
{
	int width = 512;  //!< image width (px)
	int height = 384;  //!< image height (px)
	double hfov_deg = 65.0;	 //!< horizontal field of view (deg)
	double baseline_m = 0.12;  //!< stereo baseline, left to right camera (m)
	double height_m = 1.5;	//!< optical centres above the ground (m)
	double pitch_deg = 3.0;	 //!< downward tilt of the optical axis (deg)
	double fps = 10.0;	//!< frame rate (Hz)
	WavelengthGrid grid;  //!< spectral sampling
	CameraSpectralModel spectral;  //!< channel sensitivities, white balance
	double exposure_percentile = 0.9;	//!< auto-exposure: this luma percentile of the left image...
	double exposure_target = 190.0;	 //!< ...maps to this grey level (0-255)
	double exposure_roi_top = 0.33;	 //!< fraction of image rows at the top left out of metering
	double exposure_smoothing = 0.6;  //!< weight of the previous exposure (0 = none, per-frame AE)
	bool noise = true;	//!< add shot and read noise before quantising
	double full_well_e = 9000.0;  //!< electrons at grey level 255 (sets shot noise)
	double read_noise_e = 10.0;	 //!< read noise, standard deviation (electrons)

	/** Focal length in pixels: (width/2) / tan(hfov/2). */
	double focalPx() const;
	double cx() const { return 0.5 * (width - 1); }	 //!< principal point (px), pixel centres at integers
	double cy() const { return 0.5 * (height - 1); }

	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;
	void validate() const;	//!< throws std::invalid_argument naming the key
};

/** The world: one route and what stands along it, fixed by a seed. */
struct TSimSceneOptions : public mrpt::config::CLoadableOptions
{
	uint32_t seed = 7;	//!< layout seed (tree/building placement, textures)
	double route_length_m = 300.0;	//!< arc length of the route (m)
	double route_amplitude_m = 12.0;  //!< lateral amplitude of its gentle S-curve (m)
	double road_half_width_m = 3.5;	 //!< half width of the asphalt (m)
	double sidewalk_width_m = 2.5;	//!< paved strip each side of the road (m)
	double lane_offset_m = -1.75;  //!< vehicle path relative to the road centre, + = left (m)
	double trees_end_m = 110.0;	 //!< tree-lined stretch from the start to here (m of route)
	double buildings_end_m = 210.0;	 //!< buildings from trees_end_m to here; open stretch after (m)
	double tree_spacing_m = 8.5;  //!< mean spacing of trees along each side (m)
	double canopy_gap_fraction = 0.5;	//!< fraction of the canopy shell volume without leaves
	double leaf_scale_m = 0.6;	//!< size of leaf clumps and gaps (m)
	double canopy_wind_m = 0.25;  //!< per-traversal shift of the leaf pattern (m), the "wind"
	double texture_contrast = 1.0;	//!< scales brightness texture of all materials (0 = flat)
	double texture_chroma = 1.0;  //!< scales chromatic texture (mix of two spectra; 0 = one spectrum)
	double max_distance_m = 160.0;	//!< rays stop here (sky beyond) (m)
	/** Extra spheres of a distinct purple material, world frame: x y z radius (m),
	 * several separated by ','. For geometry checks. */
	std::vector<std::array<double, 4>> markers;
	/** markers as written ("x y z r, x y z r") and read (std::invalid_argument saying what is wrong). */
	static std::string markersText(const std::vector<std::array<double, 4>>& markers);
	static std::vector<std::array<double, 4>> parseMarkers(const std::string& text);

	/** Scenery is laid out from 40 m before the route's start to 60 m past
	 * its end (Scene::layout), so a traversal may end up to this far past
	 * route_length_m and still look at 40 m of it ahead (m). */
	static constexpr double kEndMargin_m = 20.0;

	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;
	void validate() const;
};

/** One drive along the route: lighting, path, speed, seeds. */
struct TTraversal : public mrpt::config::CLoadableOptions
{
	std::string name;  //!< from the section name [traversal.<name>]
	double sun_azimuth_deg = 180.0;	 //!< clockwise from north (+y); 90 = east (+x, ahead at start)
	double sun_elevation_deg = 45.0;  //!< above the horizon (deg)
	double sun_temperature_K = 5500.0;	//!< black-body colour temperature of direct sun (K)
	double sky_temperature_K = 12000.0;	 //!< colour temperature of skylight (K)
	/** Direct-sun irradiance on a surface facing the sun, relative to the
	 * sun outside the atmosphere; < 0 = from elevation: exp(-0.3 * airmass). */
	double sun_irradiance = -1.0;
	double sky_irradiance = 0.12;  //!< skylight irradiance on a horizontal surface, same unit
	bool overcast = false;	//!< no direct sun: skylight only, no hard shadows
	double lateral_offset_m = 0.0;	//!< added to the lane offset, + = left (m)
	double weave_amplitude_m = 0.15;  //!< slow lateral weave of the path (m)
	double speed_mps = 5.0;	 //!< mean speed (m/s)
	double speed_variation = 0.2;  //!< relative amplitude of the speed's slow oscillation
	double start_s_m = 0.0;	 //!< route position of the first frame (m)
	/** Frames to render; 0 = as many as it takes to reach end_s_m (the .ini
	 * gives either `frames` or `end_s_m`, not both). */
	int frames = 80;
	/** With frames = 0: the traversal ends at the first frame at or past this
	 * route position (m), so traversals with the same start and end cover
	 * the same stretch whatever their speeds, ending within one frame's
	 * travel of each other. At most the scene's route_length_m +
	 * TSimSceneOptions::kEndMargin_m. */
	double end_s_m = 0.0;
	uint32_t wind_seed = 1;	 //!< canopy leaf-pattern shift
	uint32_t noise_seed = 1;  //!< sensor noise, speed and weave phases
	double start_time = 1.7e9;	//!< timestamp of the first frame (s, UNIX)

	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;
	void validate() const;
	/** True when the frame count follows from end_s_m (frames = 0). */
	bool endsByDistance() const { return frames == 0; }
	/** Effective direct-sun irradiance (0 when overcast or below the horizon). */
	double effectiveSunIrradiance() const;
};

/** Everything the simulator reads from sim.ini. */
struct TSimOptions : public mrpt::config::CLoadableOptions
{
	TSimCameraOptions camera;
	TSimSceneOptions scene;
	std::vector<TTraversal> traversals;	 //!< in the order listed in [sim] traversals

	/** Reads [sim] traversals = a b c, [sim.camera], [sim.scene], [traversal.a]... */
	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;

	/** Loads a file; SimOptionsError naming the file (missing, unknown key,
	 * bad value, unknown traversal section). */
	static TSimOptions FromFile(const std::string& path);

	/** t.validate(), and with end_s_m, that the end lies within this scene
	 * (end_s_m <= route_length_m + kEndMargin_m); std::invalid_argument
	 * naming the key. */
	void validateTraversal(const TTraversal& t) const;

	/** The traversal called name, or SimOptionsError listing the known ones. */
	const TTraversal& traversal(const std::string& name) const;
};

}  // namespace shadyloc::sim
