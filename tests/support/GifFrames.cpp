/* ShadyLoc tests: animated GIFs decoded by giflib (GifFrames.h). */
#include "GifFrames.h"

#include <gif_lib.h>

#include <cstring>
#include <memory>
#include <stdexcept>

namespace shadyloc::test
{
namespace
{
std::string giflibError(int e)
{
	const char* s = GifErrorString(e);
	return s ? s : "error " + std::to_string(e);
}

bool isLoopExtension(const SavedImage& im)
{
	for (int i = 0; i + 1 < im.ExtensionBlockCount; i++)
	{
		const auto& b = im.ExtensionBlocks[i];
		if (b.Function == APPLICATION_EXT_FUNC_CODE && b.ByteCount == 11 && std::memcmp(b.Bytes, "NETSCAPE2.0", 11) == 0)
			return true;
	}
	return false;
}

/** Image i drawn over `canvas`: its pixels but the transparent ones. */
void drawOver(GifFileType* gif, int i, cv::Mat& canvas, int& delay)
{
	const SavedImage& im = gif->SavedImages[i];
	GraphicsControlBlock gcb;
	gcb.TransparentColor = NO_TRANSPARENT_COLOR;
	gcb.DelayTime = 0;
	DGifSavedExtensionToGCB(gif, i, &gcb);
	delay = gcb.DelayTime;
	const ColorMapObject* map = im.ImageDesc.ColorMap ? im.ImageDesc.ColorMap : gif->SColorMap;
	if (!map) throw std::runtime_error("GIF image " + std::to_string(i) + " has no colour map");
	const auto& d = im.ImageDesc;
	for (int y = 0; y < d.Height; y++)
		for (int x = 0; x < d.Width; x++)
		{
			const int idx = im.RasterBits[y * d.Width + x];
			if (idx == gcb.TransparentColor) continue;
			const GifColorType c = map->Colors[idx];
			canvas.at<cv::Vec3b>(d.Top + y, d.Left + x) = cv::Vec3b(c.Blue, c.Green, c.Red);
		}
}
}  // namespace

TDecodedGif decodeGif(const std::string& path)
{
	int error = 0;
	std::unique_ptr<GifFileType, void (*)(GifFileType*)> gif(
		DGifOpenFileName(path.c_str(), &error), [](GifFileType* g) { DGifCloseFile(g, nullptr); });
	if (!gif) throw std::runtime_error("'" + path + "': " + giflibError(error));
	if (DGifSlurp(gif.get()) != GIF_OK) throw std::runtime_error("'" + path + "': " + giflibError(gif->Error));
	TDecodedGif out;
	out.width = gif->SWidth;
	out.height = gif->SHeight;
	cv::Mat canvas(out.height, out.width, CV_8UC3, cv::Scalar(0, 0, 0));
	for (int i = 0; i < gif->ImageCount; i++)
	{
		out.loops = out.loops || isLoopExtension(gif->SavedImages[i]);
		int delay = 0;
		drawOver(gif.get(), i, canvas, delay);
		out.frames.push_back(canvas.clone());
		out.delays.push_back(delay);
	}
	return out;
}

}  // namespace shadyloc::test
