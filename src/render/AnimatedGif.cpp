/* ShadyLoc — animated GIFs through giflib (render/AnimatedGif.h). */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/render/AnimatedGif.h>

#include <gif_lib.h>
#include <opencv2/imgproc.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace shadyloc::render
{
namespace
{
constexpr int kCubeStep = 51;  // 6 levels: 0, 51, ..., 255
constexpr int kGreysPerStep = 8;  // grey level m is 51 m / 8, m = 0..40
constexpr int kGreyLevels = 5 * kGreysPerStep + 1;

int cubeIndex(int ri, int gi, int bi) { return 36 * ri + 6 * gi + bi; }

/** Grey level m as a palette index: a cube grey, or one of the 35 after the cube. */
int greyIndex(int m)
{
	if (m % kGreysPerStep == 0) return cubeIndex(m / kGreysPerStep, m / kGreysPerStep, m / kGreysPerStep);
	return 216 + (m / kGreysPerStep) * (kGreysPerStep - 1) + (m % kGreysPerStep - 1);
}

int greyValue(int m) { return static_cast<int>(std::lround(double(kCubeStep) * m / kGreysPerStep)); }

std::array<TRgb, 256> makePalette()
{
	std::array<TRgb, 256> p{};
	for (int r = 0; r < 6; r++)
		for (int g = 0; g < 6; g++)
			for (int b = 0; b < 6; b++)
				p[cubeIndex(r, g, b)] = {uint8_t(r * kCubeStep), uint8_t(g * kCubeStep), uint8_t(b * kCubeStep)};
	for (int m = 0; m < kGreyLevels; m++)
	{
		const auto v = uint8_t(greyValue(m));
		p[greyIndex(m)] = {v, v, v};
	}
	return p;
}

int squaredDistance(const TRgb& a, int r, int g, int b)
{
	const int dr = a.r - r, dg = a.g - g, db = a.b - b;
	return dr * dr + dg * dg + db * db;
}

std::string giflibMessage(int error)
{
	const char* s = GifErrorString(error);
	return s ? s : "error " + std::to_string(error);
}
}  // namespace

const std::array<TRgb, 256>& gifPalette()
{
	static const std::array<TRgb, 256> palette = makePalette();
	return palette;
}

uint8_t nearestGifIndex(uint8_t r, uint8_t g, uint8_t b)
{
	// The cube is a product grid: its nearest entry rounds each channel. The
	// nearest grey is the level nearest the mean. The better of the two is
	// the nearest entry of the whole palette (up to the greys' rounding).
	const auto level = [](int c) { return (c + kCubeStep / 2) / kCubeStep; };
	const int cube = cubeIndex(level(r), level(g), level(b));
	const double mean = (int(r) + g + b) / 3.0;
	const int m = std::clamp(int(std::lround(mean * kGreysPerStep / kCubeStep)), 0, kGreyLevels - 1);
	const int grey = greyIndex(m);
	const auto& p = gifPalette();
	return uint8_t(squaredDistance(p[grey], r, g, b) <= squaredDistance(p[cube], r, g, b) ? grey : cube);
}

cv::Mat quantiseToGifPalette(const cv::Mat& bgr)
{
	if (bgr.type() != CV_8UC3) throw std::invalid_argument("quantiseToGifPalette: a BGR image (CV_8UC3) is needed");
	cv::Mat out(bgr.size(), CV_8UC1);
	for (int y = 0; y < bgr.rows; y++)
	{
		const auto* in = bgr.ptr<cv::Vec3b>(y);
		auto* o = out.ptr<uint8_t>(y);
		for (int x = 0; x < bgr.cols; x++) o[x] = nearestGifIndex(in[x][2], in[x][1], in[x][0]);
	}
	return out;
}

AnimatedGifWriter::AnimatedGifWriter(const std::string& path, int width, int height, int delayCentiseconds)
	: m_path(path), m_width(width), m_height(height), m_delay(delayCentiseconds)
{
	if (width <= 0 || height <= 0 || width > 65535 || height > 65535)
		throw std::invalid_argument("'" + path + "': a GIF frame must be 1..65535 px each way");
	if (delayCentiseconds < 0 || delayCentiseconds > 65535)
		throw std::invalid_argument("'" + path + "': a GIF frame's delay must be 0..65535 cs");
	// Opened here rather than by EGifOpenFileName, which makes the file
	// readable by its owner alone: the mode of every other output (umask).
	const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);
	if (fd < 0) throw std::runtime_error("'" + path + "': cannot open for writing (" + std::strerror(errno) + ")");
	int error = 0;
	m_gif = EGifOpenFileHandle(fd, &error);
	if (!m_gif)
	{
		::close(fd);
		fail("cannot open for writing", error);
	}
	try
	{
		writeHeader();
	}
	catch (...)
	{
		EGifCloseFile(m_gif, nullptr);	// the destructor does not run for a throwing constructor
		throw;
	}
}

void AnimatedGifWriter::writeHeader()
{
	EGifSetGifVersion(m_gif, true);	 // GIF89a: delays, transparency, looping
	GifColorType colours[256];
	for (size_t i = 0; i < 256; i++) colours[i] = {gifPalette()[i].r, gifPalette()[i].g, gifPalette()[i].b};
	ColorMapObject* map = GifMakeMapObject(256, colours);
	if (!map) fail("out of memory for the palette", E_GIF_ERR_NOT_ENOUGH_MEM);
	const int ok = EGifPutScreenDesc(m_gif, m_width, m_height, 8, 0, map);
	GifFreeMapObject(map);
	if (ok != GIF_OK) fail("cannot write the screen descriptor", m_gif->Error);
	// NETSCAPE2.0 application extension: loop forever (count 0).
	static const GifByteType netscape[] = "NETSCAPE2.0";
	static const GifByteType loopForever[] = {1, 0, 0};
	if (EGifPutExtensionLeader(m_gif, APPLICATION_EXT_FUNC_CODE) != GIF_OK ||
		EGifPutExtensionBlock(m_gif, 11, netscape) != GIF_OK || EGifPutExtensionBlock(m_gif, 3, loopForever) != GIF_OK ||
		EGifPutExtensionTrailer(m_gif) != GIF_OK)
		fail("cannot write the looping extension", m_gif->Error);
}

AnimatedGifWriter::~AnimatedGifWriter()
{
	if (m_gif) EGifCloseFile(m_gif, nullptr);
}

void AnimatedGifWriter::fail(const std::string& what, int giflibError) const
{
	throw std::runtime_error("'" + m_path + "': " + what + " (giflib: " + giflibMessage(giflibError) + ")");
}

cv::Mat AnimatedGifWriter::changedPart(const cv::Mat& indices, cv::Rect& box) const
{
	box = cv::Rect(0, 0, m_width, m_height);
	if (m_previous.empty()) return indices;
	const cv::Mat changed = indices != m_previous;
	box = cv::boundingRect(changed);
	if (box.empty()) box = cv::Rect(0, 0, 1, 1);  // nothing changed: one transparent pixel
	cv::Mat part(box.size(), CV_8UC1, cv::Scalar(kGifTransparentIndex));
	indices(box).copyTo(part, changed(box));
	return part;
}

void AnimatedGifWriter::writeImage(const cv::Mat& part, const cv::Rect& box, bool transparent)
{
	GraphicsControlBlock gcb;
	gcb.DisposalMode = DISPOSE_DO_NOT;	// later frames draw over this one
	gcb.UserInputFlag = false;
	gcb.DelayTime = m_delay;
	gcb.TransparentColor = transparent ? kGifTransparentIndex : NO_TRANSPARENT_COLOR;
	GifByteType ext[4];
	const size_t n = EGifGCBToExtension(&gcb, ext);
	if (EGifPutExtension(m_gif, GRAPHICS_EXT_FUNC_CODE, int(n), ext) != GIF_OK ||
		EGifPutImageDesc(m_gif, box.x, box.y, box.width, box.height, false, nullptr) != GIF_OK)
		fail("cannot write frame " + std::to_string(m_frames), m_gif->Error);
	for (int y = 0; y < part.rows; y++)
		if (EGifPutLine(m_gif, const_cast<GifPixelType*>(part.ptr<uint8_t>(y)), part.cols) != GIF_OK)
			fail("cannot write frame " + std::to_string(m_frames), m_gif->Error);
}

void AnimatedGifWriter::addFrame(const cv::Mat& bgr)
{
	if (!m_gif) throw std::logic_error("'" + m_path + "': frame added after close()");
	if (bgr.type() != CV_8UC3 || bgr.cols != m_width || bgr.rows != m_height)
		throw std::invalid_argument(
			"'" + m_path + "': frame " + std::to_string(m_frames) + " is " + std::to_string(bgr.cols) + "x" +
			std::to_string(bgr.rows) + " px of " + std::to_string(bgr.channels()) + " channel(s), not " +
			std::to_string(m_width) + "x" + std::to_string(m_height) + " BGR");
	const cv::Mat indices = quantiseToGifPalette(bgr);
	cv::Rect box;
	const cv::Mat part = changedPart(indices, box);
	writeImage(part, box, !m_previous.empty());
	m_previous = indices;
	m_frames++;
}

void AnimatedGifWriter::close()
{
	if (!m_gif) return;
	if (m_frames == 0) throw std::runtime_error("'" + m_path + "': an animation needs at least one frame");
	int error = 0;
	const int ok = EGifCloseFile(m_gif, &error);
	m_gif = nullptr;  // freed by EGifCloseFile whatever it returns
	if (ok != GIF_OK) fail("cannot finish the file", error);
}

void writeAnimatedGif(const std::string& path, const std::vector<cv::Mat>& frames, int delayCentiseconds)
{
	if (frames.empty()) throw std::invalid_argument("'" + path + "': an animation needs at least one frame");
	io::writeAtomically(path, [&](const std::string& tmp) {
		AnimatedGifWriter gif(tmp, frames.front().cols, frames.front().rows, delayCentiseconds);
		for (const auto& f : frames) gif.addFrame(f);
		gif.close();
	});
}

}  // namespace shadyloc::render
