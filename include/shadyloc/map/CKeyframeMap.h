/* ShadyLoc — the dual-channel keyframe map: an MRPT metric map
 * (mrpt::maps::CMetricMap) holding the survey's keyframes with the stereo
 * measurements of every channel, queried by the localisers through
 * map::KeyframeQueries. Creatable from MRPT .ini files (CMultiMetricMap:
 * `keyframeMap_count = 1`, options in `<prefix>_keyframeMap_00_creationOpts`),
 * serialised with versions (options included), drawn by getVisualizationInto.
 *
 * Storage: measurement coordinates are quantised to 1/16 px (landmarks and
 * their covariances are recomputed from them with the map's calibration on
 * insertion and on load, so the in-memory map equals the stored one); BRIEF
 * descriptors and pixel patches are stored as they are; every block is
 * compressed with zstd and carries a checksum, so any damaged byte is an
 * error on load. docs/map.md.
 */
#pragma once

#include <shadyloc/geometry/StereoCamera.h>
#include <shadyloc/map/MapTypes.h>

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/img/TColor.h>
#include <mrpt/maps/CMetricMap.h>

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace shadyloc
{
namespace core
{
class KeyVisitor;
}

/** Options of the keyframe map: how a survey thins and stores keyframes, and
 * how the map is drawn. Stored with the map. ([map] in config/vo*.ini, or the
 * creationOpts section of a CMultiMetricMap .ini.) Read strictly
 * (core::SettingsSection: unknown keys, bad numbers and booleans are errors
 * naming file, section and key); dumped in the canonical form that loads
 * back to the same values (core::SettingsWriter). */
struct TKeyframeMapOptions : public mrpt::config::CLoadableOptions
{
	double kf_spacing_m = 1.5;	//!< a new map keyframe after this distance along the VO path [m]
	double kf_spacing_deg = 15.0;  //!< ... or this change of heading (rotation angle) [deg]
	/** Landmarks kept per keyframe and channel (0 = all), the best by
	 * `landmark_selection` per image bucket first, so they stay spread over
	 * the image. 140 with 4-bit patches sits at the knee of the measured
	 * size-coverage curve, under 5 MB/km per channel (docs/map.md, "Size
	 * against coverage"); 0 keeps every landmark (3.6x the size). */
	int landmarks_per_keyframe = 300;
	/** How a survey ranks a keyframe's landmarks when it thins them. */
	enum class LandmarkSelection : uint8_t
	{
		Strongest = 0,	//!< by FAST response, then stereo correlation
		/** By how often the survey's own frames near the keyframe re-find the
		 * landmark (matched and a pose inlier), then as Strongest: stable,
		 * distinctive landmarks first ("keep the landmarks that localise"). */
		Reobserved = 1
	};
	LandmarkSelection landmark_selection = LandmarkSelection::Reobserved;
	/** Reobserved: survey frames within this path distance before and after
	 * the keyframe (same chain segment) are matched against its landmarks [m]. */
	double reobservation_window_m = 3.0;
	/** Reobserved: BRIEF search circle around a landmark's projection at the
	 * VO's pose of the frame [px]. */
	double reobservation_radius_px = 10.0;
	/** Reobserved: landmarks re-found in fewer frames than this are dropped
	 * even when the budget has room (0 = keep them as the budget allows). */
	int min_reobservations = 0;
	/** The depth of each kept landmark refined by the survey frames that
	 * re-found it (geometry/LandmarkDepth.h), with its sigma: matters for a
	 * live camera to the side of the survey's. */
	bool depth_from_reobservations = true;
	/** ... each re-observation's pixel noise [px] (the pair's is the
	 * channel's sigma_px): calibrated against true depth on the simulator's
	 * surveys (docs/map.md, "Depth from re-observations"). */
	double reobservation_sigma_px = 1.25;
	int selection_grid_cols = 8;  //!< buckets across the image for landmark selection
	int selection_grid_rows = 6;  //!< buckets down the image
	/** Bits kept of each pixel of the stored patches, 1..8: the low bits are
	 * replaced by the middle of their range (in memory as on disk), so the
	 * patches compress better. At equal size 4 bits localise best: 3 or 2
	 * bits buy landmarks but lose more (docs/map.md, "Size against coverage"). */
	int patch_bits = 4;
	/** The survey stores a surface normal per landmark (features/SurfaceNormals.h),
	 * so the localisers can warp its patch to the live viewpoint. */
	bool surface_normals = true;
	/** The plane of a normal is fitted to the (2r+1)^2 dense disparities around the landmark [px]. */
	int normal_window_px = 8;
	int compression_level = 9;  //!< zstd level, 1 (fast) .. 22 (small); 19 saves 3 % for 5x the time
	double index_cell_m = 10.0;	 //!< cell size of the spatial hash grid [m]
	bool draw_landmarks = false;  //!< getVisualizationInto draws landmarks, coloured by channel
	double draw_landmark_max_depth_m = 30.0;  //!< farther landmarks are not drawn [m]
	double draw_frame_every_m = 5.0;  //!< a keyframe marker (chevron) at most every this far [m]

	/** Every key of [map], declared once (core/Options.h). */
	void keys(core::KeyVisitor& v);
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;
	/** Throws std::invalid_argument naming the option. */
	void validate() const;
	bool operator==(const TKeyframeMapOptions& o) const;
};

/** "strongest" | "reobserved" (the [map] spelling). */
std::string toString(TKeyframeMapOptions::LandmarkSelection s);

class CKeyframeMap : public mrpt::maps::CMetricMap, public map::KeyframeQueries
{
	DEFINE_SERIALIZABLE(CKeyframeMap, shadyloc)

   public:
	/** Map file extension, used everywhere (".kfmap"). */
	static constexpr const char* kFileExtension = ".kfmap";
	/** Coordinates are stored as integers in 1/kPixelQuantum px. */
	static constexpr int kPixelQuantum = 16;

	CKeyframeMap() = default;

	TKeyframeMapOptions options;  //!< stored with the map

	// ---- what the map was made with ----------------------------------------
	/** Sets the camera and the channels; only on an empty map (throws otherwise). */
	void setup(
		const geometry::TStereoCalib& calib, int imageWidth, int imageHeight,
		const std::vector<map::TChannelParams>& channels);
	const geometry::TStereoCalib& calibration() const { return m_calib; }
	int imageWidth() const { return m_width; }
	int imageHeight() const { return m_height; }
	const std::vector<map::TChannelParams>& channels() const { return m_channels; }
	/** Throws std::runtime_error naming both parameter sets if live data made
	 * with `live` is not comparable with this map's channel of the same label. */
	void checkCompatible(const map::TChannelParams& live) const;

	/** Survey runs (a keyframe's `run` indexes this): the map's experiences. */
	const std::vector<std::string>& runs() const { return m_runs; }
	/** Index of a run, adding it if new. Its keyframe poses are in the frame
	 * of run `frame`: kMapFrame (0), the first run's; an earlier run that
	 * keeps a frame of its own (placed there through links); or kOwnFrame,
	 * a new frame of its own, never chained to the others. */
	uint16_t addRun(const std::string& name, int frame = kMapFrame);
	static constexpr int kMapFrame = 0;
	static constexpr int kOwnFrame = -1;
	/** The run whose frame run `run`'s poses are in (0: the map frame). */
	uint16_t runFrame(uint16_t run) const;
	bool runAnchored(uint16_t run) const { return runFrame(run) == 0; }
	/** The frame keyframe `id`'s map pose is in (runFrame of its run).
	 * Poses in different frames are unrelated. */
	uint32_t frameOf(uint32_t id) const;
	/** Verified relative poses between keyframes of different runs. */
	const std::vector<map::TExperienceLink>& links() const { return m_links; }
	/** Adds a link; throws naming the keyframes if either is unknown or both
	 * are of one run. */
	void addLink(const map::TExperienceLink& link);
	/** What loading left out and why, one line each: a link that names a
	 * keyframe the map lacks, is not a pose with a covariance, or
	 * contradicts the map poses it placed; a run whose frame names a run
	 * that founds none (kept in a frame of its own); a run without
	 * keyframes. The rest of the map loads and localises; callers report
	 * these (map-info, localise). A damaged block (checksum) is still
	 * refused whole: nothing in it can be trusted. */
	const std::vector<std::string>& loadProblems() const { return m_loadProblems; }
	/** loadProblems() as "warning: map '<path>': <problem>" lines. */
	void reportLoadProblems(std::ostream& out, const std::string& path) const;
	/** T_a_b with covariance where measurements relate a and b: along the
	 * chain in one segment, else through the link between their segments
	 * nearest both (chains composed on either side); none otherwise. */
	std::optional<map::TRelativePose> measuredRelativePose(uint32_t a, uint32_t b) const;

	// ---- building --------------------------------------------------------------
	/** Appends a keyframe (id set here). Its measurements are quantised and
	 * their landmarks and covariances recomputed with the map's calibration
	 * (what a load would give); measurements that no longer triangulate are
	 * dropped. Throws if channels do not match the map's or a coordinate
	 * cannot be stored. */
	void appendKeyframe(map::TMapKeyframe kf);

	// ---- map::KeyframeQueries -----------------------------------------------------
	size_t keyframeCount() const override { return m_keyframes.size(); }
	const map::TMapKeyframe& keyframe(uint32_t id) const override;
	size_t channelIndex(const std::string& label) const override;
	std::vector<map::TKeyframeHit> nearestKeyframes(
		const Eigen::Isometry3d& T_map_query, const map::TNearestQuery& q = {}) const override;
	std::vector<uint32_t> keyframesAlongChain(uint32_t id, double back_m, double ahead_m) const override;
	const std::vector<features::TStereoMeasurement>& measurements(
		uint32_t id, const std::string& channel) const override;
	bool sameSegment(uint32_t a, uint32_t b) const override;
	map::TRelativePose relativePose(uint32_t a, uint32_t b) const override;

	const std::vector<map::TMapKeyframe>& keyframes() const { return m_keyframes; }
	/** Keyframes that carry a ground-truth pose (TMapKeyframe::T_gt_kf). */
	size_t groundTruthCount() const;
	/** Removes every keyframe's ground-truth pose; returns how many there
	 * were. Localisation never reads it, so a map without it gives the same
	 * results (evaluation needs it: `shadyloc map-info --strip-gt`). */
	size_t stripGroundTruth();
	/** Path length along the chains (segment gaps not counted) [m]. */
	double pathLength() const;
	/** Distance along the chain from the first keyframe of its segment [m]. */
	double chainDistance(uint32_t id) const;

	// ---- files -------------------------------------------------------------------
	/** Writes the map (an MRPT archive of this one object, the file MRPT
	 * tools read with the plugin) atomically: a temporary sibling, flushed to
	 * disk, then renamed. afterChunk(bytes written so far), if given, is
	 * called after each 64 kB written (progress). */
	void saveToFile(const std::string& path, const std::function<void(size_t)>& afterChunk = {}) const;
	/** Reads a map file; throws std::runtime_error naming the file on any
	 * damage (truncation, flipped bytes, another class, unknown version). */
	static CKeyframeMap::Ptr LoadFromFile(const std::string& path);
	/** The same on the bytes of a map file in memory (the loader's whole
	 * entry point, e.g. for a fuzz target); `path` names them in errors. */
	static CKeyframeMap::Ptr LoadFromBytes(const uint8_t* data, size_t size, const std::string& path = "(memory)");

	/** Stored bytes per block, measured by serialising: the metadata block
	 * (options, calibration, channels, keyframe poses) and one block per channel. */
	struct TSizeReport
	{
		size_t meta_bytes = 0;	//!< compressed
		std::vector<size_t> channel_bytes;	//!< compressed, per channel
		std::vector<size_t> channel_raw_bytes;	//!< before compression, per channel
		std::vector<size_t> channel_measurements;  //!< measurements kept, per channel
		size_t total_bytes = 0;	 //!< whole serialised object
	};
	TSizeReport sizeReport() const;

	// ---- CMetricMap ----------------------------------------------------------------
	bool isEmpty() const override { return m_keyframes.empty(); }
	/** Writes `<prefix>.kfmap` (the map) and `<prefix>_keyframes.tum` (keyframe poses). */
	void saveMetricMapRepresentationToFile(const std::string& prefix) const override;
	/** How the map is drawn: sizes of what is drawn as geometry (a software
	 * renderer ignores line widths), a property of the picture, not stored. */
	struct TDrawStyle
	{
		/** Width of the path ribbon [m]; 0 = 1/250 of the map's extent (at least 5 cm). */
		double path_width_m = 0;
		/** Size of a keyframe marker (a chevron pointing where the camera looks) [m]; 0 = 4 path widths. */
		double marker_size_m = 0;
	};
	/** In the map frame: the path of each segment as a ribbon in the road
	 * plane (blue where measured, orange where only predicted after a VO
	 * break), a chevron at a keyframe at most every draw_frame_every_m, and,
	 * with draw_landmarks, the landmarks coloured by channel. Experiences
	 * kept in frames of their own are not drawn (their poses are unrelated
	 * to the map frame). */
	void getVisualizationInto(mrpt::opengl::CSetOfObjects& o) const override;
	void getVisualizationInto(mrpt::opengl::CSetOfObjects& o, const TDrawStyle& style) const;
	/** Colours of the drawing: the path where measured, where predicted, and
	 * the landmarks of channel c (for legends). */
	static constexpr mrpt::img::TColor kDrawColourMeasured{70, 120, 230};
	static constexpr mrpt::img::TColor kDrawColourPredicted{235, 140, 30};
	static mrpt::img::TColor drawColourOfChannel(size_t c);
	/** The summary (map-info prints it), ending with drawingSummary(). */
	std::string asString() const override;
	/** One line: what getVisualizationInto draws of this map and in which
	 * frame (landmarks only with draw_landmarks; experiences in frames of
	 * their own left out). */
	std::string drawingSummary() const;

	// Virtuals that make no sense for a keyframe map: they throw, naming the class.
	void determineMatching2D(
		const mrpt::maps::CMetricMap*, const mrpt::poses::CPose2D&, mrpt::tfest::TMatchingPairList&,
		const mrpt::maps::TMatchingParams&, mrpt::maps::TMatchingExtraResults&) const override;
	void determineMatching3D(
		const mrpt::maps::CMetricMap*, const mrpt::poses::CPose3D&, mrpt::tfest::TMatchingPairList&,
		const mrpt::maps::TMatchingParams&, mrpt::maps::TMatchingExtraResults&) const override;
	float compute3DMatchingRatio(
		const mrpt::maps::CMetricMap*, const mrpt::poses::CPose3D&,
		const mrpt::maps::TMatchingRatioParams&) const override;
	float squareDistanceToClosestCorrespondence(float, float) const override;

	MAP_DEFINITION_START(CKeyframeMap)
	TKeyframeMapOptions creationOpts;  //!< [<prefix>_creationOpts]
	MAP_DEFINITION_END(CKeyframeMap)

   private:
	geometry::TStereoCalib m_calib;
	int m_width = 0, m_height = 0;	//!< image size [px]
	std::vector<map::TChannelParams> m_channels;
	std::vector<std::string> m_runs;
	std::vector<uint16_t> m_runFrame;  //!< per run: see runFrame()
	std::vector<map::TExperienceLink> m_links;
	std::vector<std::string> m_loadProblems;  //!< see loadProblems()
	std::vector<map::TMapKeyframe> m_keyframes;
	std::vector<double> m_chainDist;  //!< per keyframe, see chainDistance()
	/** Spatial hash grid over camera centres: cell key -> keyframe ids. */
	std::unordered_map<uint64_t, std::vector<uint32_t>> m_grid;

	uint64_t cellKey(const Eigen::Vector3d& p) const;
	void indexKeyframe(uint32_t id);
	void rebuildIndex();
	/** Quantises in place and recomputes landmark and covariance; false if
	 * the quantised measurement does not triangulate. */
	bool quantise(features::TStereoMeasurement& m, const map::TChannelParams& ch) const;
	void appendLoaded(map::TMapKeyframe kf);  //!< as stored: no quantisation, index updated

	void internal_clear() override;
	bool internal_insertObservation(
		const mrpt::obs::CObservation& obs,
		const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;
	double internal_computeObservationLikelihood(
		const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& takenFrom) const override;
	bool internal_canComputeObservationLikelihood(const mrpt::obs::CObservation&) const override
	{
		return false;  // see internal_computeObservationLikelihood
	}
};

}  // namespace shadyloc
