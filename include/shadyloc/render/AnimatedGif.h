/* ShadyLoc — animated GIFs of BGR frames, through giflib's EGif* API
 * (Debian libgif-dev), e.g. `shadyloc localise --gif`.
 *
 * Quantiser: one fixed palette for every frame, the 6x6x6 colour cube (216
 * entries, steps of 51) plus 35 greys between the cube's six, so that grey
 * has 41 levels (steps of 51/8). The frames it is made for are mostly the
 * channels' grey images (kept to within 4 levels) with a few flat colours
 * drawn over them (lines, markers, text: within the cube's step); a fixed
 * palette keeps the colours of the map and of the matches the same from
 * frame to frame (an adaptive one, such as median cut, shifts them as the
 * content changes), and needs no pass over the frames before writing.
 * No dithering: at 41 grey levels banding is slight, and dither noise
 * would defeat GIF's LZW compression (and shimmer between frames).
 *
 * Frames after the first carry only what changed: pixels equal to the
 * previous frame's are written as the transparent index over the bounding
 * box of the change (disposal "do not dispose"), which LZW packs into
 * almost nothing where the picture stands still.
 */
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

struct GifFileType;	 // giflib's, private to the implementation

namespace shadyloc::render
{
struct TRgb
{
	uint8_t r = 0, g = 0, b = 0;
};

/** The palette index that marks "unchanged" in frames after the first. */
constexpr int kGifTransparentIndex = 251;
/** Largest error of a grey pixel (r = g = b) after quantisation [levels]. */
constexpr double kGifGreyError = 4.0;
/** Largest error of any pixel, as the Euclidean RGB distance (half the
 * cube's step in each channel) [levels]. */
constexpr double kGifColourError = 44.2;

/** The fixed palette (see the file comment); entries past 250 are unused. */
const std::array<TRgb, 256>& gifPalette();
/** The index of the palette colour nearest (r, g, b). */
uint8_t nearestGifIndex(uint8_t r, uint8_t g, uint8_t b);
/** A BGR image (CV_8UC3) as palette indices (CV_8UC1). */
cv::Mat quantiseToGifPalette(const cv::Mat& bgr);

/** Writes an animation frame by frame into an open file. The file is the
 * caller's to place atomically (io::OutputTransaction, io::writeAtomically):
 * after an error it is incomplete. */
class AnimatedGifWriter
{
   public:
	/** Opens `path` (created or truncated) for frames of width x height px
	 * shown for `delayCentiseconds` each, looping forever. Throws
	 * std::runtime_error naming the file. */
	AnimatedGifWriter(const std::string& path, int width, int height, int delayCentiseconds);
	/** Closes the file if close() was not called (never throws). */
	~AnimatedGifWriter();
	AnimatedGifWriter(const AnimatedGifWriter&) = delete;
	AnimatedGifWriter& operator=(const AnimatedGifWriter&) = delete;

	/** One BGR frame (CV_8UC3) of the writer's size; throws
	 * std::invalid_argument for another size or type, std::runtime_error on
	 * a write error. */
	void addFrame(const cv::Mat& bgr);
	/** Writes the trailer and closes; throws std::runtime_error on error or
	 * if no frame was added. */
	void close();
	size_t frameCount() const { return m_frames; }

   private:
	/** The screen descriptor with the palette, GIF89a, looping. */
	void writeHeader();
	/** The rectangle of frame `indices` that differs from the previous one,
	 * unchanged pixels there made transparent (the whole frame first). */
	cv::Mat changedPart(const cv::Mat& indices, cv::Rect& box) const;
	void writeImage(const cv::Mat& part, const cv::Rect& box, bool transparent);
	void fail(const std::string& what, int giflibError) const;

	GifFileType* m_gif = nullptr;
	std::string m_path;
	int m_width, m_height, m_delay;
	size_t m_frames = 0;
	cv::Mat m_previous;	 //!< the last frame's indices
};

/** A whole animation written atomically (a failed write leaves no file). */
void writeAnimatedGif(const std::string& path, const std::vector<cv::Mat>& frames, int delayCentiseconds);

}  // namespace shadyloc::render
