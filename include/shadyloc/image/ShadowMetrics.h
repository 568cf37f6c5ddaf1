/* ShadyLoc — how strongly an image channel shows a cast shadow, measured on a
 * tripod-aligned pair of the same view with and without the shadow (e.g. the
 * UIUC shadow pairs of Guo, Dai and Hoiem, CVPR 2011). */
#pragma once

#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <vector>

namespace shadyloc::image
{
struct ShadowMaskOptions
{
	/** A pixel is in the shadow when log(free) - log(shadow) exceeds this in
	 * every channel (linear response; 0.4 = at least 1.5 times darker). */
	double minLogDrop = 0.4;
	/** Erosion radius (px) removing the mask's rim, where the pair's 1-2 px
	 * misalignment and the penumbra mix lit and shadowed pixels. */
	int erodeRadius = 3;
	/** Pixels darker than this code value in the free image are ignored
	 * (noise and clipping dominate their logs). */
	int minCode = 8;
};

/** CV_8U mask (255 = shadow) from the BGR 8-bit free/shadow pair, comparing
 * sRGB-linearised responses. */
cv::Mat shadowMaskFromPair(const cv::Mat& freeBgr, const cv::Mat& shadowBgr, const ShadowMaskOptions& o = {});

/** The step a shadow makes in one 8-bit channel, relative to texture:
 * median over mask pixels of |shadow - free|, divided by the channel's robust
 * texture spread (1.4826 * median absolute deviation) in the free image over
 * the same pixels. Small = the shadow hardly shows against the texture. */
struct ShadowStep
{
	double step = 0;	 //!< median |shadow - free| over the mask, grey levels
	double spread = 0;	 //!< robust texture spread of the free image there, grey levels
	double relative() const { return step / std::max(1.0, spread); }
};
ShadowStep relativeShadowStep(const cv::Mat& channelFree, const cv::Mat& channelShadow, const cv::Mat& mask);

/** The same metric on the channel's values at the mask pixels (free[i] and
 * shadow[i] at one pixel), for channels that are not 8-bit images (the alpha
 * calibration evaluates it on float invariants). Needs >= 100 values. */
ShadowStep relativeShadowStepOfValues(const std::vector<double>& freeValues, const std::vector<double>& shadowValues);

}  // namespace shadyloc::image
