/* ShadyLoc — does a camera's data suit the invariant channel? The checks
 * behind calibrate-alpha's verdict (docs/calibration.md, "Cameras that suit
 * the invariant channel").
 *
 * The invariant (McManus et al. 2014) assumes linear (or known-curve) sensor
 * responses at full resolution in every channel. JPEG's 4:2:0 chroma is coded
 * in 8x8 blocks of a half-resolution plane: the invariant, which is chroma
 * only, then shows a 16-pixel block grid where FAST corners pile up. Clipped
 * channels break the ratios. And an estimate of alpha at a search bound, or
 * methods that disagree, say the data do not follow the model.
 */
#pragma once

#include <shadyloc/image/InvariantCalibration.h>

#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace shadyloc::image
{
/** How strongly the invariant shows a JPEG block grid. Per line between
 * pixels 16k-1 and 16k (4:2:0 chroma blocks), rows and columns: the mean
 * |step| of I across it (log units, clamped at 0.5 so that a few strong
 * edges do not decide) over the mean across the lines within 8 px that lie
 * on no multiple of 8; ratio16 is the median of those ratios over every line
 * of every image, ratio8 the same for the lines at odd multiples of 8
 * (luma blocks). Per line and the median: a scene edge that happens to lie
 * on the grid moves one ratio, while JPEG blocks raise them all. 1 = no grid. */
struct TBlockGrid
{
	double ratio16 = 1, ratio8 = 1;
};
TBlockGrid blockGridOf(const std::vector<cv::Mat>& images, const InvariantParams& p);

/** Share of pixels (below the skipped top rows) with a channel at or above
 * in.maxCode: the pixels whose ratios clipping broke. */
double saturatedShare(const std::vector<cv::Mat>& images, const TCalibrationInput& in);

/** Chroma subsampling in a JPEG file's frame header (SOF): "4:2:0", "4:2:2",
 * "4:4:4" or "other"; "" when the file is not a baseline/progressive JPEG. */
std::string jpegChromaSubsampling(const std::string& path);

/** A transfer curve tried on shadow pairs: with the right curve, a shadow
 * scales each channel's linear response by one factor over its whole area,
 * so log(free) - log(shadow) does not depend on the surface's brightness.
 * drift: the median over pairs and channels of |slope| of that log ratio
 * against the pixel's mean log response, in the shadow mask. A pure power
 * law (any gamma) leaves it unchanged (it scales both logs alike, and the
 * invariant only by a factor, which the mapping absorbs); sRGB's offset and
 * a camera's S-shaped tone curve do not. */
struct TToneCurveDrift
{
	std::string curve;	//!< "none" (also any gamma) or "srgb"
	double drift = 0;
	int items = 0;	//!< pair-channels with a usable mask
};
/** The stated curve (in.linearisation) first, then the other one. */
std::vector<TToneCurveDrift> toneCurveDrifts(const std::vector<TShadowPair>& pairs, const TCalibrationInput& in);

enum class Suitability
{
	Suitable,
	Doubtful,  //!< the estimate and the channel may be fine; check before trusting them
	Unsuitable	//!< no confident alpha from these data; the channel will not help as it is
};
std::string toString(Suitability s);  //!< "suitable" | "doubtful" | "unsuitable"

/** Where a verdict turns: each limit is argued in docs/calibration.md. */
struct TSuitabilityLimits
{
	/** Block grid ratio: the simulator's linear frames measure 0.98-0.99,
	 * the same frames as JPEG 1.40 (quality 90) and 1.58 (75), the UIUC
	 * JPEGs 2.72. */
	double gridDoubtful = 1.15, gridUnsuitable = 1.5;
	/** Share of saturated pixels: the simulator's frames (blown sky and
	 * sunlit walls) have 16-25 %, and suit the channel; beyond a third the channel is undefined on
	 * much of the image, beyond half on most of it. */
	double clippedDoubtful = 1.0 / 3.0, clippedUnsuitable = 0.5;
	/** The stated curve's drift over the other's: the data follow the other
	 * curve better (and the stated drift is at least toneDriftFloor). */
	double toneDriftRatio = 1.5, toneDriftFloor = 0.05;
	/** Estimates of trusted methods further apart than this: the issue's
	 * held-out camera missed its reference by 0.05. */
	double methodsApart = 0.05;
};

/** What the verdict is made from. */
struct TSuitabilityEvidence
{
	bool gridMeasured = false;
	TBlockGrid grid;
	double saturated = 0;  //!< saturatedShare()
	std::vector<TToneCurveDrift> tone;	//!< toneCurveDrifts(); empty without shadow pairs
	size_t jpegFiles = 0;  //!< image files read that are JPEGs
	std::vector<std::string> subsampledFiles;  //!< JPEGs with chroma subsampling ("name (4:2:0)")
	std::vector<TAlphaCurve> curves;  //!< every method's estimate; empty with a known alpha
	std::string chosenMethod;  //!< the estimate that goes into OUT.ini
	TAlphaSearch search;
};

/** One reason, machine-readable by its code (block-grid, chroma-subsampled,
 * clipping, tone-curve, at-search-bound, methods-disagree) and readable by its text. */
struct TSuitabilityReason
{
	std::string code;
	Suitability severity = Suitability::Doubtful;
	std::string text;
};

struct TSuitabilityVerdict
{
	Suitability verdict = Suitability::Suitable;
	std::vector<TSuitabilityReason> reasons;
	std::vector<std::string> checks;  //!< what was measured, one line each, for the report
	void add(const std::string& code, Suitability severity, const std::string& text);
	/** The command's exit status: 0 suitable, 3 doubtful, 4 unsuitable
	 * (1 and 2 are errors and usage). */
	int exitCode() const;
};

/** The verdict on the evidence. The entropy estimate takes no part in the
 * method comparison: its minimum follows 8-bit quantisation lattices on
 * real data (docs/calibration.md), so it disagrees with sound data too. */
TSuitabilityVerdict judgeSuitability(const TSuitabilityEvidence& e, const TSuitabilityLimits& l = {});

}  // namespace shadyloc::image
