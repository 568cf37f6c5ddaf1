// Uses an installed ShadyLoc: transforms one pixel and prints its value.
#include <shadyloc/image/ColourTransforms.h>

#include <iostream>

int main()
{
	cv::Mat px(1, 1, CV_8UC3, cv::Scalar(40, 120, 200)), out;
	shadyloc::image::InvariantTransform().apply(px, out);
	std::cout << int(out.at<uint8_t>(0, 0)) << "\n";
	return 0;
}
