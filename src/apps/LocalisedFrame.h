/* ShadyLoc — one frame of a localisation run as a picture, for an animation
 * (`shadyloc localise --gif`) or a sequence of stills (`--view N
 * --view-images`): the live left image of each localiser's channel, as the
 * localiser saw it, with the matches it made against the map (inliers of
 * its solve green, the others red) side by side, over the top-down view of
 * the map and the live path so far (LocalisedView.h). Offscreen, no window
 * system. */
#pragma once

#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <vector>

namespace shadyloc::render
{
class AnimatedGifWriter;
}

namespace shadyloc::apps
{
/** A channel's live left image (grey, shared with the frame's measurements). */
struct TChannelImage
{
	std::string channel;
	cv::Mat left;
};

/** The picture's size for `width`: one panel per channel in a row, at the
 * camera's aspect, over a top-down view a third as tall as it is wide. */
cv::Size localisedFrameSize(int width, size_t channels, cv::Size camera);

/** The picture (BGR) of the last of `ups`, with its localisers' channels'
 * images from `images` (all of one size). Throws std::runtime_error if a
 * localiser's channel has no image or the top-down view cannot be rendered. */
cv::Mat composeLocalisedFrame(
	const CKeyframeMap& map, const std::vector<localisation::TLocalisationUpdate>& ups,
	const std::vector<TChannelImage>& images, int width);

/** What a run records as pictures. */
struct TFrameRecording
{
	std::string gifPath;  //!< the animation's file ("": none); the caller places it atomically
	int gifEvery = 1;  //!< every N-th frame into the animation
	double gifFps = 8;	//!< frames shown per second
	std::string viewDir;  //!< stills as PNGs here, named by viewFileName()
	int viewEvery = 0;	//!< every N-th frame a still (0: none)
	int width = 480;  //!< of the pictures [px]
};

/** Records a run: hooks into the system to keep the channels' images of the
 * frames it pictures, then onFrame() composes and writes what is due. */
class LocalisedFrameRecorder
{
   public:
	LocalisedFrameRecorder(localisation::LocalisationSystem& sys, const TFrameRecording& o);
	~LocalisedFrameRecorder();
	/** After each frame: the last of `ups` pictured if due. */
	void onFrame(const CKeyframeMap& map, const std::vector<localisation::TLocalisationUpdate>& ups);
	/** Finishes the animation (throws if it could not be written). */
	void finish();
	size_t gifFrames() const;

   private:
	bool due(size_t frame) const;

	localisation::LocalisationSystem* m_sys;  //!< whose frame hook this is
	TFrameRecording m_opts;
	std::vector<TChannelImage> m_images;  //!< of the last frame due
	std::unique_ptr<render::AnimatedGifWriter> m_gif;
};

}  // namespace shadyloc::apps
