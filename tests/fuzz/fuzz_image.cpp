/* Fuzz target: the checked image readers (io::checkImageBytes, then
 * cv::imdecode). Our structure checks are instrumented; Debian's OpenCV and
 * its codec libraries are not (checking stops at their entry points). */
#include "FuzzSupport.h"

#include <shadyloc/io/ImageFile.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	if (size > (1u << 20)) return 0;
	try
	{
		// A small pixel limit keeps each decode fast.
		const cv::Mat m = shadyloc::io::decodeImageBytes(data, size, "fuzz", cv::IMREAD_UNCHANGED, 1u << 22);
		if (m.empty()) shadyloc::fuzz::contractViolated("decodeImageBytes", "returned an empty image");
	}
	catch (const shadyloc::io::ImageFileError&)
	{
	}
	catch (const std::exception& e)
	{
		shadyloc::fuzz::contractViolated("image reader threw something other than ImageFileError", e.what());
	}
	return 0;
}
