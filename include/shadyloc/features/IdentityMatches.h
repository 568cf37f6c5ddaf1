/* ShadyLoc — how many features of one image are found again in another
 * image of the same view at the same place (identity geometry: a
 * tripod-aligned pair such as the UIUC shadow pairs of Guo, Dai and Hoiem,
 * CVPR 2011), and how many of them sit on a JPEG block grid. The features
 * are the VO's: single-scale FAST spread by a grid, BRIEF (McManus et al.
 * 2014, Section II-A). */
#pragma once

#include <opencv2/core/mat.hpp>

namespace shadyloc::features
{
/** The invariant channel's settings of config/vo.ini. */
struct TIdentityMatchOptions
{
	int fastThreshold = 5;	//!< [grey levels]
	int gridCols = 8, gridRows = 6, perCell = 20;
	double presmoothSigma = 1.0;  //!< Gaussian smoothing before detection [px]
	double ratio = 0.8;	 //!< Lowe's ratio test on the two nearest Hamming distances
	/** A match is correct within this distance of its keypoint [px]: the
	 * pairs are aligned to within 1-2 px (shared/data/README.md). */
	double maxOffsetPx = 3.0;
	/** b's image is a's moved by this [px]: zero for a tripod pair; a
	 * shift that is no multiple of gridPeriod puts the two images' block
	 * grids at different places of the scene, as camera motion would, so
	 * that block corners no longer match themselves. */
	cv::Point2f shift{0, 0};
	int gridPeriod = 16;  //!< JPEG 4:2:0 chroma block [px]
	/** Keypoints closer than this to a block line count as on the grid
	 * [px]: FAST (radius 3) fires 1-2 px beside a step, so the pile-up
	 * shows at those distances. */
	int gridBand = 3;
};

struct TIdentityMatches
{
	int keypoints = 0;	//!< FAST corners described in the first image
	int matches = 0;  //!< passing the ratio test
	int correct = 0;  //!< within maxOffsetPx of their own place
	int correctOffGrid = 0;	 //!< of those, not on the grid band (so not block corners matched to themselves)
	/** Coordinates (x and y of each keypoint of a) within gridBand of a
	 * block line, and the others: gridPileUp() of them. */
	int coordsNearGrid = 0, coordsOffGrid = 0;
};

/** Features of `a` (8-bit grey) matched in `b` (same size, the same view)
 * by nearest Hamming distance over all of b's features. */
TIdentityMatches identityMatches(const cv::Mat& a, const cv::Mat& b, const TIdentityMatchOptions& o = {});

/** Keypoint coordinates per unit length of the grid band over those
 * elsewhere: 1 = no pile-up on the block grid. */
double gridPileUp(double coordsNearGrid, double coordsOffGrid, const TIdentityMatchOptions& o = {});

}  // namespace shadyloc::features
