/* ShadyLoc — stereo measurements of one rectified grey stereo pair: FAST
 * corners (single-scale, or OpenCV's ORB on a scale pyramid with orientation:
 * [features] descriptor) spread over the image by grid buckets, stereo correspondence by
 * ZNCC patch matching along the epipolar row (candidates: right-image FAST
 * corners within the disparity range), sub-pixel refinement (parabola),
 * left-right consistency and ambiguity rejection, a BRIEF (or ORB) descriptor, a pixel
 * patch and a triangulated landmark with its covariance per measurement
 * (McManus et al. 2014, Section II-A).
 *
 * The same code runs on either channel: the input is just a grey image pair
 * (monochrome, or the illumination-invariant image).
 */
#pragma once

#include <shadyloc/features/Brief.h>
#include <shadyloc/geometry/StereoCamera.h>

#include <mrpt/config/CLoadableOptions.h>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include <array>
#include <vector>

namespace shadyloc::core
{
class KeyVisitor;
}

namespace shadyloc::features
{
/** Side of the stored pixel patch (for sub-pixel refinement against later frames). */
constexpr int kPatchSize = 9;

/** What detects the left corners and describes them. Both give 256-bit
 * descriptors compared by Hamming distance; they do not compare with each
 * other (a map records which one made it). */
enum class DescriptorKind : uint8_t
{
	/** Single-scale FAST, BRIEF without orientation (McManus et al. 2014, Section II-A). */
	Brief = 0,
	/** OpenCV's ORB (Rublee et al., ICCV 2011): FAST on a scale pyramid,
	 * intensity-centroid orientation, rotated learned BRIEF tests. */
	Orb = 1,
};
/** "brief" / "orb". */
const char* toString(DescriptorKind k);

/** Side of ORB's descriptor patch at its level [px]: OpenCV's default, the
 * size its learned test pattern was made for; also its edge threshold. */
constexpr int kOrbPatchSize = 31;

/** One stereo measurement: a left-right correspondence and what follows from it. */
struct TStereoMeasurement
{
	float uL = 0, v = 0;  //!< left keypoint (integer FAST corner, refined later if at all) [px]
	float uR = 0;  //!< right keypoint, sub-pixel, on the left row v [px]
	float response = 0;	 //!< FAST score of the left corner
	float zncc = 0;	 //!< stereo patch correlation in [-1, 1]
	TBriefDescriptor desc;	//!< BRIEF of the left keypoint
	std::array<uint8_t, kPatchSize * kPatchSize> patch{};  //!< left pixels around (uL, v), row-major
	Eigen::Vector3d P = Eigen::Vector3d::Zero();  //!< landmark in the left camera frame [m]
	Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();	//!< covariance of P [m^2]
	/** Unit normal of the surface at P, facing the camera, in the left camera
	 * frame; zero when unknown (SurfaceNormals.h: map keyframes only). */
	Eigen::Vector3f normal = Eigen::Vector3f::Zero();
	/** Standard deviation of the true disparity where other views refined it
	 * (map landmarks: geometry/LandmarkDepth.h) [px]; 0 = the pair's own,
	 * sigma_px on each of uL, v, uR. */
	float sigma_d = 0;
};

/** Stage times of one extraction [ms]. */
struct TFeatureTimings
{
	double detect_ms = 0, stereo_ms = 0, describe_ms = 0;
};

/** All measurements of one stereo frame. */
struct TStereoFrame
{
	std::vector<TStereoMeasurement> meas;
	size_t cornersLeft = 0, cornersRight = 0;  //!< FAST corners kept per eye
	TFeatureTimings timings;
	cv::Mat left;  //!< the left grey image (shared, not copied)
	cv::Mat right;	//!< the right grey image the stereo matches were found in (shared)
	cv::Mat smoothed;  //!< left as BRIEF sees it (BriefExtractor::smooth): warped descriptors sample it
};

/** Corners spread by a grid: the image (W x H) is cut into cols x rows
 * cells and each keeps its `perCell` strongest corners (all if perCell <= 0).
 * Corners closer than `border` px to an edge are dropped. */
void spreadOverGrid(
	const std::vector<cv::KeyPoint>& all, int W, int H, int cols, int rows, int perCell, int border,
	std::vector<cv::KeyPoint>& out);

/** FAST corners (OpenCV) spread by a grid (spreadOverGrid). */
void detectFastGrid(
	const cv::Mat& grey8, int threshold, int cols, int rows, int perCell, int border,
	std::vector<cv::KeyPoint>& out);

/** ZNCC in [-1, 1] between the (2r+1)^2 patches centred at (xa, ya) in a and
 * (xb, yb) in b; both must lie inside their images. -1 for a flat patch. */
float zncc(const cv::Mat& a, int xa, int ya, const cv::Mat& b, int xb, int yb, int r);

/** Vertex offset in [-0.5, 0.5] of the parabola through (-1, cm), (0, c0), (1, cp). */
inline float parabolaPeak(float cm, float c0, float cp)
{
	const float den = cm - 2 * c0 + cp;
	if (!(den < -1e-9f)) return 0.f;  // not a maximum: keep the integer position
	const float o = 0.5f * (cm - cp) / den;
	return o < -0.5f ? -0.5f : (o > 0.5f ? 0.5f : o);
}

/** Sub-pixel x in `right` of the (2r+1)^2 patch of `left` centred at integer
 * (xl, y), on row y, starting from x0 (e.g. the parabola's vertex): Gauss-Newton
 * on sum (R(x + dx) - g L(xl + dx) - c)^2 over (x, g, c), R sampled along the
 * row by cubic convolution (Keys, a = -1/2), at most `iterations` steps. The
 * parabola through three integer-shift correlation scores pulls estimates
 * towards integer shifts ("pixel locking", Shimizu & Okutomi, ICCV 2001); since
 * uL is an integer corner, that locks disparities towards integers. Returns x0
 * when the iteration leaves x0 +- 1 px or the image, or is ill-conditioned. */
float refineRowShift(
	const cv::Mat& left, int xl, int y, const cv::Mat& right, float x0, int r, int iterations);

/** Sub-pixel position in `img` of a size x size template (row-major, centred
 * on its middle pixel), starting from (x0, y0) (e.g. a 2D parabola's vertex):
 * Gauss-Newton on sum (I(x + dx, y + dy) - g T(dx, dy) - c)^2 over (x, y, g, c),
 * I sampled by separable cubic convolution (Keys, a = -1/2), at most
 * `iterations` steps. The 2D counterpart of refineRowShift (no pixel locking).
 * Returns false (x, y untouched) when the iteration leaves (x0, y0) +- 1 px or
 * the image, or is ill-conditioned. */
bool refinePatch2D(
	const uint8_t* tmpl, int size, const cv::Mat& img, float x0, float y0, int iterations, float& x,
	float& y);

/** ZNCC of a stored kPatchSize^2 patch against the image window centred at
 * integer (x, y) (the window must fit); -1 for a flat patch or window. */
float patchZncc(const std::array<uint8_t, kPatchSize * kPatchSize>& patch, const cv::Mat& img, int x, int y);

/** Where is a stored patch in `img`, near the integer pixel (x0, y0)? The
 * ZNCC hill-climb over the 3x3 neighbourhood for at most `radius_px` steps
 * to a peak of at least `min_zncc`, a parabola through the peak, then
 * refinePatch2D for `iterations` steps. Returns false (x, y untouched) when
 * no such peak lies within reach or inside the image. Shared by the VO's
 * keyframe matcher and the localisers (the paper's sub-pixel refinement by
 * patch matching). */
bool locatePatch(
	const std::array<uint8_t, kPatchSize * kPatchSize>& patch, const cv::Mat& img, int x0, int y0, int radius_px,
	float min_zncc, int iterations, float& x, float& y);

/** The right-image column of the left pixel (xl, y) near a predicted uR:
 * the ZNCC of (2r+1)^2 windows at every integer column within +-halfRange of
 * uRPred, the best at least minZncc and not on the range's edge, then the
 * parabola and refineRowShift (`iterations` steps). False when no such peak
 * exists or a window leaves an image. For a point found without a stereo
 * feature (a landmark's patch located in the left image). */
bool matchAlongRow(
	const cv::Mat& left, int xl, int y, const cv::Mat& right, float uRPred, int halfRange, int r, float minZncc,
	int iterations, float& uR);

/** Options of StereoFeatureExtractor ([features] in config/vo.ini). */
struct TStereoFeatureOptions : public mrpt::config::CLoadableOptions
{
	int fast_threshold = 12;  //!< FAST intensity threshold [grey levels]
	int grid_cols = 8;	//!< buckets across the image
	int grid_rows = 6;	//!< buckets down the image
	int max_per_cell = 20;	//!< strongest left corners kept per bucket
	int max_per_cell_right = 60;  //!< per bucket in the right image (more: matches must be among them)
	double min_disparity = 1.0;	 //!< smallest true disparity D = fx b / Z searched [px]
	double max_disparity = 96.0;  //!< largest true disparity searched [px]
	int row_tolerance = 1;	//!< right corners within +-this many rows are candidates [px]
	int patch_radius = 3;  //!< stereo ZNCC patch is (2r+1)^2 [px]
	double min_zncc = 0.8;	//!< weakest accepted stereo correlation
	double max_ambiguity = 0.6;	 //!< reject if (1-best)/(1-second best) exceeds this
	double lr_tolerance_px = 1.0;  //!< left-right consistency: reverse match within this [px]
	/** Depth-discontinuity check: the four windows beside the patch (shifted
	 * by 2 patch_radius + 1: left, right, up, down) must also correlate at the
	 * found disparity at least this well; a corner on an object's silhouette
	 * fails it (its background half lies at another disparity). -1 disables.
	 * 0.3 with shifted_window_check (which catches silhouettes more
	 * selectively), 0.5 without it (docs/vo.md, Middlebury). */
	double min_zncc_shifted = 0.3;
	int brief_patch_size = 32;	//!< BRIEF patch side S [px]
	uint32_t brief_seed = 0x5ad710c;  //!< BRIEF test pattern seed (maps and live runs must agree)
	double sigma_px = 0.5;	//!< pixel noise of uL, v, uR for landmark covariances [px]
	double max_depth = 80.0;  //!< landmarks farther than this are dropped [m]
	/** Gaussian pre-smoothing of both images before detection, stereo and
	 * patches (0 = off) [px]. Pixel noise that is independent in the two eyes
	 * (e.g. the invariant image's log-ratio noise) makes FAST fire on noise and
	 * breaks the stereo correlation; smoothing trades a little localisation for that. */
	double presmooth_sigma = 0.0;
	/** Gauss-Newton steps refining the stereo match's sub-pixel uR after the
	 * parabola fit (refineRowShift); 0 = the parabola only. */
	int subpixel_iterations = 5;
	/** Verify each match by ZNCC at every integer shift of the disparity
	 * range (not only at right-image corners): the dense maximum must be the
	 * match (+-1 px) and no other local maximum may pass max_ambiguity. */
	bool dense_check = true;
	/** With dense_check: the four windows shifted by (+-patch_radius,
	 * +-patch_radius), each holding the corner pixel at one of its corners,
	 * must (when textured) also have their dense maximum at the match +-1 px;
	 * rejects corners on depth edges whose centred window follows the other
	 * surface (shiftable windows, Fusiello et al. 1997). */
	bool shifted_window_check = true;
	/** A shifted window's best shift elsewhere (> 1 px from the match) rejects
	 * the match only when its ZNCC exceeds the window's own score at the match
	 * (+-1 px) by more than this [ZNCC units]; 0 = any better shift rejects. */
	double shifted_window_margin = 0.0;
	/** Detector and descriptor of the left corners (and detector of the
	 * right-image candidates): FAST + BRIEF, or ORB. Descriptor-defining. */
	DescriptorKind descriptor = DescriptorKind::Brief;
	/** ORB: pyramid levels (1 = single scale, orientation only). Descriptor-defining. */
	int orb_levels = 8;
	/** ORB: size ratio of neighbouring pyramid levels (> 1). Descriptor-defining. */
	double orb_scale_factor = 1.2;
	/** ORB: the right image's stereo candidates from this many pyramid levels
	 * (from the finest), 0 = all (orb_levels). The matcher correlates at full
	 * resolution: a coarse level's corner is a candidate within a pixel or two. */
	int orb_right_levels = 0;

	void keys(core::KeyVisitor& v);  //!< every key, declared once (core/Options.h)
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
	void dumpToTextStream(std::ostream& out) const override;
	/** Throws std::invalid_argument naming the bad option. */
	void validate() const;
};

/** What a corner is detected for: to be described (ORB: its orientation
 * is measured), or only as a candidate position (the right image's stereo
 * candidates, which are never described). */
enum class CornerUse
{
	Described,
	Candidates
};

/** Detection and description of one image's corners as the options say
 * (FAST + BRIEF, or ORB): the one place both stereo frames and single images
 * (the image localiser) get their features from. */
class CornerDescriber
{
   public:
	explicit CornerDescriber(const TStereoFeatureOptions& o);

	/** Smallest distance of a described corner to an image edge [px]. */
	int border() const { return m_border; }

	/** Corners of grey8 spread by the options' grid, `perCell` per cell, at
	 * least `border` px from the edges. BRIEF: single-scale FAST. ORB: FAST
	 * on ORB's pyramid (positions in level-0 pixels, octave set, and the
	 * angle where `use` is Described), ranked by FAST score so the map's
	 * 16-bit response keeps its meaning: the corners cv::ORB::detect finds. */
	void detect(
		const cv::Mat& grey8, int perCell, int border, std::vector<cv::KeyPoint>& out,
		CornerUse use = CornerUse::Described) const;

	/** Descriptors at corners of grey8 (as detect() returned them).
	 * desc[i] is valid where ok[i]; a corner whose patch does not fit is not.
	 * BRIEF: the smoothed image its tests read goes to `smoothed` when given
	 * (warped descriptors sample it later); ORB leaves it empty. */
	void describe(
		const cv::Mat& grey8, const std::vector<cv::KeyPoint>& kps, std::vector<TBriefDescriptor>& desc,
		std::vector<uint8_t>& ok, cv::Mat* smoothed = nullptr) const;

   private:
	TStereoFeatureOptions m_opts;
	BriefExtractor m_brief;
	int m_border = 0;
};

class StereoFeatureExtractor
{
   public:
	using TOptions = TStereoFeatureOptions;

	explicit StereoFeatureExtractor(const TOptions& o = TOptions());
	const TOptions& options() const { return m_opts; }

	/** Measurements of a rectified CV_8UC1 pair of equal size. Throws
	 * std::invalid_argument on wrong image types or sizes. */
	void process(
		const cv::Mat& left8, const cv::Mat& right8, const geometry::TStereoCalib& calib,
		TStereoFrame& out) const;

	const CornerDescriber& corners() const { return m_corners; }

   private:
	TOptions m_opts;
	CornerDescriber m_corners;
};

}  // namespace shadyloc::features
