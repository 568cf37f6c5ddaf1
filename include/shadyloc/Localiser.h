/* ShadyLoc — the public face for MRPT applications: localise live colour
 * (or filtered) stereo observations against a keyframe map (a `shadyloc survey` .kfmap),
 * one result per frame shaped like MOLA's LocalizationUpdate.
 *
 *   shadyloc::LocaliserOptions opts;
 *   opts.loadFromConfigFile(mrpt::config::CConfigFile("localise.ini"), "");
 *   shadyloc::Localiser loc("noon.kfmap", opts);
 *   for (each observation obs of the rawlog)
 *       if (auto r = loc.process(obs)) use(r->pose);
 *
 * This header includes MRPT and the standard library only (a test checks
 * it): the system behind it (localisation/LocalisationSystem.h) may change
 * without applications noticing. Link the target shadyloc::localisation.
 */
#pragma once

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/core/Clock.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace shadyloc
{
namespace localisation
{
struct TLocalisationUpdate;	 // the full per-frame record (localisation/LocalisationSystem.h)
}

/** What the localiser reads from an .ini: the localisation system's sections
 * ([localise], [localiser], [localiser.<channel>], [vo], [features], their
 * per-channel sections, the channel filter sections; docs/localisation.md),
 * every one read by the project's strict settings reader (an unknown key or
 * section, or a bad value, throws naming file, section and key), and the
 * application's own keys in the section passed to loadFromConfigFile. */
struct LocaliserOptions : public mrpt::config::CLoadableOptions
{
	/** The live colour stereo camera ("" = the first colour stereo
	 * observation not labelled as one of the system's channels). Key
	 * sensor_label. */
	std::string sensor_label;
	/** >= 0: start near this map keyframe instead of by a search of the
	 * whole map. Key start_keyframe. */
	int start_keyframe = -1;
	/** The localisation system's sections as .ini text (every section of
	 * the loaded config but the application's own). */
	std::string system_config;
	/** Names the config in errors (the file it was loaded from). */
	std::string source = "(options)";

	/** `section` ("" = none) holds sensor_label and start_keyframe; every
	 * other section is the system's, and all are checked before this returns. */
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section) override;
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const override;
};

/** How a frame's pose was obtained. */
enum class LocalisationStatus : uint8_t
{
	Localised,	//!< a localiser's fix against the map was used on this frame
	DeadReckoning,	//!< no fix now; the pose is the last fix moved by visual odometry
	NoPlace	 //!< no place known yet (or lost for good): the pose fields are meaningless
};
std::string toString(LocalisationStatus s);

/** One frame's result (the shape of MOLA's LocalizationUpdate). */
struct LocalisationUpdate
{
	mrpt::Clock::time_point timestamp;	//!< the observation's own timestamp
	/** The frame `pose` is in: "map" (the first experience's), or
	 * "map/<run>" for a map experience kept in a frame of its own (linked to
	 * no other: poses in two frames are unrelated). */
	std::string reference_frame = "map";
	/** The localiser whose fix was used ("mono", "invariant", or "joint":
	 * both channels' matches in one solve), "none" otherwise. */
	std::string method = "none";
	LocalisationStatus status = LocalisationStatus::NoPlace;
	/** The live left camera in the map frame, covariance over MRPT's
	 * (x, y, z, yaw, pitch, roll) [m^2, m rad, rad^2]. */
	mrpt::poses::CPose3DPDFGaussian pose;
	/** The same relative to the map keyframe it was found against. */
	mrpt::poses::CPose3DPDFGaussian pose_in_keyframe;
	uint32_t keyframe_id = 0;
	/** The used fix's inlier fraction (inliers / matches, 0..1); 0 without a fix. */
	double quality = 0;
	int frames_since_fix = 0;  //!< 0 on a frame with a fix
};

/** Localises one live stereo camera against one keyframe map. Not
 * thread-safe: one thread feeds it (it runs its channels in parallel
 * itself, [localise] threads). */
class Localiser
{
   public:
	/** Loads the map file (.kfmap); throws naming it, or the config at fault
	 * (descriptor parameters that differ from the map's, channels it lacks). */
	Localiser(const std::string& mapFile, const LocaliserOptions& opts);
	/** A map already in memory: a shadyloc keyframe map (else throws
	 * std::invalid_argument); shared, not copied. */
	Localiser(mrpt::maps::CMetricMap::Ptr map, const LocaliserOptions& opts);
	~Localiser();
	Localiser(Localiser&&) noexcept;
	Localiser& operator=(Localiser&&) noexcept;

	/** One observation of a rawlog or a driver. The live camera's stereo
	 * observations (CObservationStereoImages, rectified) are its colour pair
	 * (every channel made from it) or, labelled <camera><suffix>, its
	 * channels' grey pairs (a rawlog made by `shadyloc filter`, or one
	 * without the colour pairs): the colour pair is used if the first frame
	 * has one, else every channel's grey pair, read from its own
	 * observation. A result comes when a frame is
	 * complete (the colour pair; the last of the channels' pairs of one
	 * timestamp); any other observation gives none. Throws (naming the
	 * observation and frame) if the live camera's colour pair is grey or has
	 * no right image, or if the channels' observations do not pair up (same
	 * timestamp, calibration and size, one of each per frame). */
	std::optional<LocalisationUpdate> process(const mrpt::obs::CObservation::Ptr& obs);

	/** The live camera's sensor label ("" until the first frame when chosen automatically). */
	const std::string& sensorLabel() const;
	/** The map (for drawing: getVisualizationInto). */
	const mrpt::maps::CMetricMap& map() const;
	/** The last frame's full record: every localiser's result, VO, timing.
	 * Include <shadyloc/localisation/LocalisationSystem.h> to read it (its
	 * fields are the project's, not part of this face). Throws
	 * std::logic_error before the first frame. */
	const localisation::TLocalisationUpdate& lastDiagnostics() const;
	/** Forgets the place and the VO (a new run against the same map). */
	void reset();

   private:
	struct Impl;
	std::unique_ptr<Impl> m_impl;
};

}  // namespace shadyloc
