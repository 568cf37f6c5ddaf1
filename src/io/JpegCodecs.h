/* ShadyLoc — internal: frees the libjpeg codecs an exception abandoned
 * (see JpegErrors.cpp). */
#pragma once

#include <cstdint>

namespace shadyloc::io::detail
{
/** On destruction, frees every libjpeg codec this thread created since
 * construction and nobody destroyed. MRPT's JPEG decoder has no clean-up on
 * its error paths: wrap each call that may decode an MRPT image in one, so an
 * exception leaving it leaks nothing. */
class JpegCodecReaper
{
   public:
	JpegCodecReaper();
	~JpegCodecReaper();
	JpegCodecReaper(const JpegCodecReaper&) = delete;
	JpegCodecReaper& operator=(const JpegCodecReaper&) = delete;

   private:
	uint64_t m_mark = 0;
};
}  // namespace shadyloc::io::detail
