/* ShadyLoc tests: animated GIFs (render/AnimatedGif.h) read back through
 * giflib's decoder, the quantiser's error bounds, a failed write leaving
 * nothing; `shadyloc localise`'s picture options refused with clear errors. */
#include "../support/GifFrames.h"
#include "../support/TestSupport.h"

#include <shadyloc/render/AnimatedGif.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>

using namespace shadyloc::render;
namespace fs = std::filesystem;

namespace
{
double rgbDistance(const cv::Vec3b& a, const cv::Vec3b& b)
{
	const double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
	return std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

cv::Vec3b paletteBgr(int index)
{
	const TRgb c = gifPalette()[size_t(index)];
	return {c.b, c.g, c.r};
}

/** Frames like the localiser's pictures: a grey gradient that moves (the
 * camera image), a static coloured band (the map), a square that walks. */
std::vector<cv::Mat> testFrames(int count, cv::Size size)
{
	std::vector<cv::Mat> frames;
	for (int k = 0; k < count; k++)
	{
		cv::Mat f(size, CV_8UC3, cv::Scalar(255, 255, 255));
		for (int y = 0; y < size.height / 2; y++)
			for (int x = 0; x < size.width; x++)
				f.at<cv::Vec3b>(y, x) = cv::Vec3b::all(uint8_t((x * 255 / size.width + 7 * k + y) % 256));
		cv::rectangle(f, cv::Rect(0, size.height / 2, size.width, 6), cv::Scalar(196, 98, 31), cv::FILLED);
		cv::rectangle(f, cv::Rect(4 + 6 * k, size.height - 14, 8, 8), cv::Scalar(14, 130, 230), cv::FILLED);
		frames.push_back(f);
	}
	return frames;
}

/** No staged temporary (".<name>.tmp-<pid>...") left in `dir`. */
void expectNoTemporaries(const std::string& dir)
{
	for (const auto& e : fs::directory_iterator(dir))
		EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}
}  // namespace

// The palette: the 6x6x6 cube, 41 greys in all, every entry its own nearest.
TEST(RenderGif, PaletteIsTheCubeAndFortyOneGreys)
{
	std::set<int> greys;
	for (int i = 0; i < kGifTransparentIndex; i++)
	{
		const TRgb c = gifPalette()[size_t(i)];
		if (c.r == c.g && c.g == c.b) greys.insert(c.r);
		EXPECT_EQ(gifPalette()[nearestGifIndex(c.r, c.g, c.b)].r, c.r) << i;
	}
	EXPECT_EQ(greys.size(), 41u);
	EXPECT_EQ(*greys.begin(), 0);
	EXPECT_EQ(*greys.rbegin(), 255);
	for (int r = 0; r <= 255; r += 51)
		for (int b = 0; b <= 255; b += 51)
		{
			const TRgb c = gifPalette()[nearestGifIndex(uint8_t(r), 0, uint8_t(b))];
			EXPECT_TRUE(c.r == r && c.g == 0 && c.b == b) << r << " " << b;
		}
}

// Every grey within kGifGreyError; random colours within kGifColourError and
// within a level of the true nearest entry (found by brute force).
TEST(RenderGif, QuantiserErrorWithinItsBounds)
{
	for (int v = 0; v <= 255; v++)
	{
		const TRgb c = gifPalette()[nearestGifIndex(uint8_t(v), uint8_t(v), uint8_t(v))];
		EXPECT_TRUE(c.r == c.g && c.g == c.b) << v;
		EXPECT_LE(std::abs(c.r - v), kGifGreyError) << v;
	}
	std::mt19937 rng(7);
	std::uniform_int_distribution<int> level(0, 255);
	for (int i = 0; i < 20000; i++)
	{
		const cv::Vec3b bgr(uint8_t(level(rng)), uint8_t(level(rng)), uint8_t(level(rng)));
		const double err = rgbDistance(paletteBgr(nearestGifIndex(bgr[2], bgr[1], bgr[0])), bgr);
		double best = 1e9;
		for (int p = 0; p < kGifTransparentIndex; p++) best = std::min(best, rgbDistance(paletteBgr(p), bgr));
		EXPECT_LE(err, kGifColourError) << bgr;
		EXPECT_LE(err, best + 1.0) << bgr;
	}
}

// Written, decoded back by giflib: the frame count, size, delay and looping
// as asked, every pixel of every frame as shown within the quantiser's error
// of the input; frames after the first carry only the change.
TEST(RenderGif, GiflibDecodesFramesWithinTheQuantiserError)
{
	const std::string dir = shadyloc::test::tempDir("render_gif");
	const auto frames = testFrames(6, {96, 64});
	const std::string path = dir + "/anim.gif";
	std::vector<cv::Mat> withStill = frames;
	withStill.push_back(frames.back().clone());	 // nothing changes: a 1 px image
	writeAnimatedGif(path, withStill, 12);
	const auto gif = shadyloc::test::decodeGif(path);
	EXPECT_EQ(gif.width, 96);
	EXPECT_EQ(gif.height, 64);
	ASSERT_EQ(gif.frames.size(), withStill.size());
	EXPECT_TRUE(gif.loops);
	for (size_t k = 0; k < withStill.size(); k++)
	{
		EXPECT_EQ(gif.delays[k], 12) << k;
		double worstGrey = 0, worst = 0;
		for (int y = 0; y < 64; y++)
			for (int x = 0; x < 96; x++)
			{
				const cv::Vec3b in = withStill[k].at<cv::Vec3b>(y, x), out = gif.frames[k].at<cv::Vec3b>(y, x);
				const double e = rgbDistance(in, out);
				worst = std::max(worst, e);
				if (in[0] == in[1] && in[1] == in[2]) worstGrey = std::max(worstGrey, e / std::sqrt(3.0));
			}
		EXPECT_LE(worstGrey, kGifGreyError) << "frame " << k;
		EXPECT_LE(worst, kGifColourError) << "frame " << k;
	}
	// The last frame repeats the one before: it costs a few bytes, not a frame.
	const auto size = fs::file_size(path);
	writeAnimatedGif(dir + "/shorter.gif", frames, 12);
	EXPECT_LT(size - fs::file_size(dir + "/shorter.gif"), 40u);
	expectNoTemporaries(dir);
}

// A frame of another size or type is refused naming it; a failed write
// leaves no file and an earlier file untouched; no frame, no file.
TEST(RenderGif, FailedWriteLeavesNoPartialOutput)
{
	const std::string dir = shadyloc::test::tempDir("render_gif_fail");
	auto frames = testFrames(3, {48, 32});
	frames.push_back(cv::Mat(30, 48, CV_8UC3, cv::Scalar::all(0)));
	try
	{
		writeAnimatedGif(dir + "/bad.gif", frames, 10);
		ADD_FAILURE() << "a frame of another size was accepted";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("frame 3 is 48x30"), std::string::npos) << e.what();
	}
	EXPECT_FALSE(fs::exists(dir + "/bad.gif"));
	{
		std::ofstream(dir + "/earlier.gif") << "earlier";
	}
	EXPECT_THROW(writeAnimatedGif(dir + "/earlier.gif", frames, 10), std::invalid_argument);
	EXPECT_EQ(shadyloc::test::fileContents(dir + "/earlier.gif"), "earlier");
	EXPECT_THROW(writeAnimatedGif(dir + "/none.gif", {}, 10), std::invalid_argument);
	EXPECT_FALSE(fs::exists(dir + "/none.gif"));
	{
		AnimatedGifWriter w(dir + "/grey.gif", 48, 32, 10);
		EXPECT_THROW(w.addFrame(cv::Mat(32, 48, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
		EXPECT_THROW(w.close(), std::runtime_error);  // no frame
	}
	EXPECT_THROW(AnimatedGifWriter(dir + "/no/such/dir/x.gif", 48, 32, 10), std::runtime_error);
	expectNoTemporaries(dir);
}

// `shadyloc localise`'s picture options: each misuse refused naming the
// option, before any work and with nothing written.
TEST(GifApp, BadPictureOptionsNameTheOption)
{
	const std::string dir = shadyloc::test::tempDir("gif_app");
	{
		std::ofstream(dir + "/map.gif") << "not a map";
		std::ofstream(dir + "/live.rawlog") << "not a rawlog";
	}
	const std::string base =
		shadyloc::test::appPath() + " localise -q -m " + dir + "/map.gif -i " + dir + "/live.rawlog -o " + dir + "/out";
	const std::vector<std::pair<std::string, std::string>> cases = {
		{" --gif-every 2", "--gif-every and --gif-fps go with --gif"},
		{" --gif " + dir + "/a.gif --gif-every 0", "--gif-every: 0 is out of range"},
		{" --gif " + dir + "/a.gif --gif-fps 0.5", "--gif-fps: 0.5 is out of range"},
		{" --gif " + dir + "/a.png", "--gif: '" + dir + "/a.png' is not a .gif file name"},
		{" --view-images", "--view-images goes with --view N"},
		{" --frame-width 320", "--frame-width goes with --gif or --view-images"},
		{" --gif " + dir + "/map.gif", "--gif"},
		{" --gif " + dir + "/out/a.gif", "--gif"},
		{" --gif " + dir + "/missing/a.gif", "--gif"},
	};
	for (const auto& [args, message] : cases)
	{
		std::string out;
		EXPECT_NE(shadyloc::test::runCommand(base + args, &out), 0) << args;
		EXPECT_NE(out.find(message), std::string::npos) << args << "\n" << out;
	}
	EXPECT_EQ(shadyloc::test::fileContents(dir + "/map.gif"), "not a map");
	EXPECT_FALSE(fs::exists(dir + "/out"));
	EXPECT_FALSE(fs::exists(dir + "/a.gif"));
	expectNoTemporaries(dir);
}
