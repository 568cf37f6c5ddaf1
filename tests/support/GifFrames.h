/* ShadyLoc tests: an animated GIF read back through giflib's decoder
 * (DGif*), each frame composed over the ones before it as a viewer shows it. */
#pragma once

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace shadyloc::test
{
struct TDecodedGif
{
	int width = 0, height = 0;	//!< the logical screen [px]
	std::vector<cv::Mat> frames;  //!< BGR, as shown, one per image
	std::vector<int> delays;  //!< per frame [cs]
	bool loops = false;	 //!< a NETSCAPE2.0 looping extension was found
};

/** Decodes `path`; throws std::runtime_error with giflib's message. */
TDecodedGif decodeGif(const std::string& path);

}  // namespace shadyloc::test
