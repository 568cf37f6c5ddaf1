/* ShadyLoc — libjpeg's fatal errors as C++ exceptions, and no codec leaked
 * when an exception leaves MRPT's JPEG decoder.
 *
 * MRPT decodes the JPEG-compressed colour images inside rawlogs
 * (CImage::serializeFrom -> loadFromStreamAsJPEG) with libjpeg's standard
 * error manager, whose error_exit prints a message and calls exit(): one
 * corrupt image inside a rawlog would end the whole program, naming neither
 * the file nor the object, and skipping every clean-up (output transactions
 * included). And when anything throws between its jpeg_create_decompress()
 * and jpeg_destroy_decompress() (its own source manager on an empty stream,
 * our reader on a short read, the allocation bound on an image size read from
 * a corrupt header), the codec's memory is never freed.
 *
 * So libshadyloc defines a few libjpeg entry points; programs linking it find
 * them before libjpeg's (the dynamic linker searches the libraries a program
 * names before their own dependencies), and each calls libjpeg's own:
 *  - jpeg_std_error installs an error_exit that frees the codec and throws;
 *  - jpeg_Create{Compress,Decompress} record each codec's memory manager and
 *    the thread that made it, jpeg_destroy{,_compress,_decompress} drop it;
 *  - a JpegCodecReaper frees, when it goes out of scope, the codecs its
 *    thread made since it was built and nobody destroyed: their owner's stack
 *    frame was unwound, but the memory manager lives on the heap, and
 *    jpeg_destroy() needs nothing else.
 * Code that installs its own error_exit (OpenCV's codecs) and destroys its
 * codecs is unaffected. Throwing through libjpeg is safe: it is C with unwind
 * tables. MRPT's own programs that load our plugin module keep libjpeg's
 * behaviour (a module loaded later does not interpose). */
#include "JpegCodecs.h"

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <dlfcn.h>
#include <jpeglib.h>

namespace
{
/** libjpeg's own definition of `name` (the next one after ours). */
template <class Fn>
Fn libjpeg(const char* name)
{
	void* sym = dlvsym(RTLD_NEXT, name, "LIBJPEG_6.2");
	if (!sym) sym = dlsym(RTLD_NEXT, name);
	if (!sym)
	{
		std::fprintf(stderr, "shadyloc: libjpeg's %s not found\n", name);
		std::abort();
	}
	return reinterpret_cast<Fn>(sym);
}

void realDestroy(j_common_ptr cinfo)
{
	static const auto fn = libjpeg<void (*)(j_common_ptr)>("jpeg_destroy");
	fn(cinfo);
}

// ---- the codecs alive, by owner struct -----------------------------------
struct LiveCodec
{
	const void* owner;	//!< the jpeg_{de,}compress_struct (its caller's storage)
	jpeg_memory_mgr* mem;  //!< the codec's memory manager (heap: outlives the owner)
	std::thread::id thread;
	uint64_t serial;
};

std::mutex g_mutex;
std::vector<LiveCodec> g_live;
uint64_t g_serial = 0;

[[noreturn]] void throwingErrorExit(j_common_ptr cinfo);

jpeg_error_mgr* releaseErrors()
{
	static jpeg_error_mgr err = []
	{
		jpeg_error_mgr e{};
		jpeg_std_error(&e);	 // ours, below: libjpeg's manager with our error_exit
		return e;
	}();
	return &err;
}

/** Frees a codec whose owner struct is gone: jpeg_destroy() only reads the
 * memory manager (and the error manager, should it fail). */
void releaseOrphan(jpeg_memory_mgr* mem)
{
	jpeg_common_struct stand_in{};
	stand_in.err = releaseErrors();
	stand_in.mem = mem;
	realDestroy(&stand_in);
}

void forget(const void* owner)
{
	std::lock_guard<std::mutex> lock(g_mutex);
	for (size_t i = 0; i < g_live.size(); i++)
		if (g_live[i].owner == owner)
		{
			g_live.erase(g_live.begin() + std::ptrdiff_t(i));
			return;
		}
}

void remember(j_common_ptr cinfo)
{
	jpeg_memory_mgr* orphan = nullptr;
	{
		std::lock_guard<std::mutex> lock(g_mutex);
		for (size_t i = 0; i < g_live.size(); i++)
			if (g_live[i].owner == cinfo)
			{
				// A new codec where an undestroyed one lived: that one's owner
				// frame is gone (its storage is being reused).
				orphan = g_live[i].mem;
				g_live.erase(g_live.begin() + std::ptrdiff_t(i));
				break;
			}
		g_live.push_back({cinfo, cinfo->mem, std::this_thread::get_id(), ++g_serial});
	}
	if (orphan) releaseOrphan(orphan);
}

void destroyCodec(j_common_ptr cinfo)
{
	forget(cinfo);
	realDestroy(cinfo);
}

[[noreturn]] void throwingErrorExit(j_common_ptr cinfo)
{
	char message[JMSG_LENGTH_MAX] = {0};
	(*cinfo->err->format_message)(cinfo, message);
	// The caller never reaches its own jpeg_destroy_*(): free the codec now.
	destroyCodec(cinfo);
	throw std::runtime_error(std::string("JPEG image: ") + message);
}
}  // namespace

namespace shadyloc::io::detail
{
JpegCodecReaper::JpegCodecReaper()
{
	std::lock_guard<std::mutex> lock(g_mutex);
	m_mark = g_serial;
}

JpegCodecReaper::~JpegCodecReaper()
{
	std::vector<jpeg_memory_mgr*> orphans;
	{
		std::lock_guard<std::mutex> lock(g_mutex);
		const auto self = std::this_thread::get_id();
		for (size_t i = 0; i < g_live.size();)
			if (g_live[i].thread == self && g_live[i].serial > m_mark)
			{
				orphans.push_back(g_live[i].mem);
				g_live.erase(g_live.begin() + std::ptrdiff_t(i));
			}
			else
				i++;
	}
	for (auto* mem : orphans) releaseOrphan(mem);
}
}  // namespace shadyloc::io::detail

// ---- the interposed libjpeg entry points ----------------------------------
extern "C"
{
	struct jpeg_error_mgr* jpeg_std_error(struct jpeg_error_mgr* err)
	{
		static const auto fn = libjpeg<jpeg_error_mgr* (*)(jpeg_error_mgr*)>("jpeg_std_error");
		fn(err);
		err->error_exit = &throwingErrorExit;
		return err;
	}

	void jpeg_CreateDecompress(j_decompress_ptr cinfo, int version, size_t structsize)
	{
		static const auto fn = libjpeg<void (*)(j_decompress_ptr, int, size_t)>("jpeg_CreateDecompress");
		fn(cinfo, version, structsize);
		remember(reinterpret_cast<j_common_ptr>(cinfo));
	}

	void jpeg_CreateCompress(j_compress_ptr cinfo, int version, size_t structsize)
	{
		static const auto fn = libjpeg<void (*)(j_compress_ptr, int, size_t)>("jpeg_CreateCompress");
		fn(cinfo, version, structsize);
		remember(reinterpret_cast<j_common_ptr>(cinfo));
	}

	void jpeg_destroy(j_common_ptr cinfo) { destroyCodec(cinfo); }
	void jpeg_destroy_decompress(j_decompress_ptr cinfo) { destroyCodec(reinterpret_cast<j_common_ptr>(cinfo)); }
	void jpeg_destroy_compress(j_compress_ptr cinfo) { destroyCodec(reinterpret_cast<j_common_ptr>(cinfo)); }
}
