/* ShadyLoc — checked image file reading.
 *
 * cv::imread decodes what it can: a JPEG cut short comes back with its
 * missing rows filled grey and no error. These functions first check the
 * file's structure, then decode: a PNG must have valid chunks (CRC-32) up to
 * IEND, a JPEG every segment up to its EOI marker, a PPM/PGM, BMP or TIFF
 * all the pixel bytes its header announces. Dimensions are read from the
 * header and refused above a limit before anything is decoded. Every error
 * names the file.
 */
#pragma once

#include <opencv2/core/mat.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace shadyloc::io
{
/** Bad or unreadable image file; what() names the file and the reason. */
class ImageFileError : public std::runtime_error
{
   public:
	using std::runtime_error::runtime_error;
};

/** Largest image accepted by default: 100 megapixels (10000 x 10000). */
constexpr uint64_t kMaxImagePixels = 100'000'000;

/** What the header says. */
struct TImageFileInfo
{
	std::string format;	 //!< "PNG", "JPEG", "PNM", "BMP", "TIFF"
	uint32_t width = 0, height = 0;	 //!< [px]
	int channels = 0;	 //!< as stored (palette PNG: 3)
};

/** Checks the structure of an image held in memory (`name` for messages).
 * Throws ImageFileError if it is truncated, corrupt, of an unknown format,
 * or larger than maxPixels. */
TImageFileInfo checkImageBytes(
	const uint8_t* data, size_t size, const std::string& name, uint64_t maxPixels = kMaxImagePixels);

/** checkImageBytes() on a file. */
TImageFileInfo checkImageFile(const std::string& path, uint64_t maxPixels = kMaxImagePixels);

/** Checks, then decodes (flags as for cv::imread). Never returns an empty
 * matrix: throws ImageFileError naming the file instead. */
cv::Mat readImageFile(
	const std::string& path, int flags = cv::IMREAD_UNCHANGED, uint64_t maxPixels = kMaxImagePixels);

/** checkImageBytes(), then cv::imdecode. */
cv::Mat decodeImageBytes(
	const uint8_t* data, size_t size, const std::string& name, int flags = cv::IMREAD_UNCHANGED,
	uint64_t maxPixels = kMaxImagePixels);

/** Throws ImageFileError if OpenCV cannot write `path`'s format (told by its
 * extension), naming the extension and the usual ones. */
void checkImageWritable(const std::string& path);

}  // namespace shadyloc::io
