/* ShadyLoc — libjpeg's fatal errors as C++ exceptions.
 *
 * MRPT decodes the JPEG-compressed colour images inside rawlogs
 * (CImage::serializeFrom -> loadFromStreamAsJPEG) with libjpeg's standard
 * error manager, whose error_exit prints a message and calls exit(): one
 * corrupt image inside a rawlog would end the whole program, naming neither
 * the file nor the object, and skipping every clean-up (output transactions
 * included). We define jpeg_std_error here; programs linking libshadyloc find
 * it before libjpeg's (the dynamic linker searches the libraries a program
 * names before their own dependencies). It fills in libjpeg's standard
 * manager, then replaces error_exit with one that frees the codec's memory
 * and throws, which the rawlog reader reports as corrupt data at that object.
 * Code that installs its own error_exit afterwards (OpenCV's codecs) is
 * unaffected. Throwing through libjpeg is safe: it is C with unwind tables
 * and holds no resources outside the pools jpeg_destroy() frees. */
#include <cstddef>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <dlfcn.h>
#include <jpeglib.h>

namespace
{
[[noreturn]] void throwingErrorExit(j_common_ptr cinfo)
{
	char message[JMSG_LENGTH_MAX] = {0};
	(*cinfo->err->format_message)(cinfo, message);
	// The caller never reaches its own jpeg_destroy_*(): free the pools now.
	jpeg_destroy(cinfo);
	throw std::runtime_error(std::string("JPEG image: ") + message);
}

using StdErrorFn = struct jpeg_error_mgr* (*)(struct jpeg_error_mgr*);

StdErrorFn libjpegStdError()
{
	static const StdErrorFn real = []
	{
		void* sym = dlvsym(RTLD_NEXT, "jpeg_std_error", "LIBJPEG_6.2");
		if (!sym) sym = dlsym(RTLD_NEXT, "jpeg_std_error");
		if (!sym)
		{
			std::fputs("shadyloc: libjpeg's jpeg_std_error not found\n", stderr);
			std::abort();
		}
		return reinterpret_cast<StdErrorFn>(sym);
	}();
	return real;
}
}  // namespace

extern "C" struct jpeg_error_mgr* jpeg_std_error(struct jpeg_error_mgr* err)
{
	libjpegStdError()(err);
	err->error_exit = &throwingErrorExit;
	return err;
}
