/* ShadyLoc — checked image file reading (see ImageFile.h). Structure after
 * the PNG specification (W3C, 2003), JPEG (ITU-T T.81), Netpbm, BMP
 * (BITMAPINFOHEADER) and TIFF 6.0. */
#include <shadyloc/io/ImageFile.h>

#include <opencv2/imgcodecs.hpp>

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

namespace shadyloc::io
{
namespace
{
/** Bounds-checked reader over the file's bytes. */
struct Bytes
{
	const uint8_t* p;
	size_t n;
	const std::string& name;

	[[noreturn]] void fail(const std::string& why) const { throw ImageFileError("'" + name + "': " + why); }
	void need(size_t at, size_t len, const char* what) const
	{
		if (at > n || len > n - at)
			fail(std::string("truncated ") + what + " (file ends at byte " + std::to_string(n) + ")");
	}
	uint32_t be32(size_t at) const
	{
		need(at, 4, "header");
		return uint32_t(p[at]) << 24 | uint32_t(p[at + 1]) << 16 | uint32_t(p[at + 2]) << 8 | p[at + 3];
	}
	uint16_t be16(size_t at) const
	{
		need(at, 2, "header");
		return static_cast<uint16_t>(p[at] << 8 | p[at + 1]);
	}
	uint32_t le32(size_t at) const
	{
		need(at, 4, "header");
		return uint32_t(p[at]) | uint32_t(p[at + 1]) << 8 | uint32_t(p[at + 2]) << 16 | uint32_t(p[at + 3]) << 24;
	}
	uint16_t le16(size_t at) const
	{
		need(at, 2, "header");
		return static_cast<uint16_t>(p[at] | p[at + 1] << 8);
	}
};

void checkSize(const Bytes& b, TImageFileInfo& info, uint64_t maxPixels)
{
	if (info.width == 0 || info.height == 0)
		b.fail(info.format + " header gives an empty image (" + std::to_string(info.width) + "x" +
			   std::to_string(info.height) + ")");
	const uint64_t px = uint64_t(info.width) * info.height;
	if (px > maxPixels || info.width > (1u << 30) || info.height > (1u << 30))
		b.fail(
			"claims " + std::to_string(info.width) + "x" + std::to_string(info.height) + " pixels, more than the " +
			std::to_string(maxPixels / 1000000) + " megapixel limit (corrupt header?)");
}

TImageFileInfo checkPng(const Bytes& b, uint64_t maxPixels)
{
	TImageFileInfo info;
	info.format = "PNG";
	size_t at = 8;
	bool seenIhdr = false, seenIdat = false;
	for (;;)
	{
		b.need(at, 12, "PNG chunk");
		const uint32_t len = b.be32(at);
		if (len > 0x7fffffffu) b.fail("corrupt PNG chunk length");
		b.need(at + 8, size_t(len) + 4, "PNG chunk");
		const uint8_t* type = b.p + at + 4;
		const std::string t(reinterpret_cast<const char*>(type), 4);
		const uLong crc = crc32(crc32(0L, Z_NULL, 0), type, static_cast<uInt>(len + 4));
		if (crc != b.be32(at + 8 + len)) b.fail("corrupt PNG chunk '" + t + "' (CRC-32 mismatch)");
		if (!seenIhdr)
		{
			if (t != "IHDR" || len != 13) b.fail("PNG without an IHDR header chunk");
			info.width = b.be32(at + 8);
			info.height = b.be32(at + 12);
			const int colourType = b.p[at + 17];
			static const int channels[7] = {1, 0, 3, 3, 2, 0, 4};
			if (colourType > 6 || channels[colourType] == 0)
				b.fail("PNG colour type " + std::to_string(colourType) + " is invalid");
			info.channels = channels[colourType];
			checkSize(b, info, maxPixels);
			seenIhdr = true;
		}
		else if (t == "IDAT")
			seenIdat = true;
		else if (t == "IEND")
		{
			if (!seenIdat) b.fail("PNG without image data (no IDAT chunk)");
			return info;
		}
		at += 12 + size_t(len);
	}
}

TImageFileInfo checkJpeg(const Bytes& b, uint64_t maxPixels)
{
	TImageFileInfo info;
	info.format = "JPEG";
	size_t at = 2;	// after SOI
	bool seenFrame = false, seenScan = false;
	auto truncated = [&] { b.fail("truncated JPEG: the data ends before its EOI marker (file cut short?)"); };
	for (;;)
	{
		if (at >= b.n) truncated();
		if (b.p[at] != 0xFF) b.fail("corrupt JPEG: a marker was expected at byte " + std::to_string(at));
		while (at < b.n && b.p[at] == 0xFF) at++;  // fill bytes
		if (at >= b.n) truncated();
		const uint8_t m = b.p[at++];
		if (m == 0xD9)	// EOI
		{
			if (!seenScan) b.fail("JPEG without image data (no scan before EOI)");
			return info;
		}
		if (m == 0xD8 || m == 0x00) b.fail("corrupt JPEG: unexpected marker at byte " + std::to_string(at - 1));
		if ((m >= 0xD0 && m <= 0xD7) || m == 0x01) continue;  // RSTn, TEM: no length
		if (at + 2 > b.n) truncated();
		const size_t len = b.be16(at);
		if (len < 2) b.fail("corrupt JPEG segment length at byte " + std::to_string(at));
		if (at + len > b.n) truncated();
		const bool sof = (m >= 0xC0 && m <= 0xCF) && m != 0xC4 && m != 0xC8 && m != 0xCC;
		if (sof)
		{
			if (len < 8) b.fail("corrupt JPEG frame header");
			info.height = b.be16(at + 3);
			info.width = b.be16(at + 5);
			info.channels = b.p[at + 7];
			checkSize(b, info, maxPixels);
			seenFrame = true;
		}
		at += len;
		if (m == 0xDA)	// SOS: entropy-coded data up to the next marker
		{
			if (!seenFrame) b.fail("corrupt JPEG: scan before the frame header");
			seenScan = true;
			for (;;)
			{
				const void* ff = std::memchr(b.p + at, 0xFF, b.n - at);
				if (!ff) truncated();
				at = static_cast<size_t>(static_cast<const uint8_t*>(ff) - b.p);
				if (at + 1 >= b.n) truncated();
				const uint8_t next = b.p[at + 1];
				if (next == 0x00 || (next >= 0xD0 && next <= 0xD7) || next == 0xFF)
				{
					at += next == 0xFF ? 1 : 2;	 // stuffed byte, restart marker, fill
					continue;
				}
				break;	// a marker: back to the segment loop
			}
		}
	}
}

TImageFileInfo checkPnm(const Bytes& b, uint64_t maxPixels)
{
	TImageFileInfo info;
	info.format = "PNM";
	const char kind = static_cast<char>(b.p[1]);
	info.channels = kind == '6' ? 3 : 1;
	size_t at = 2;
	uint64_t v[3] = {0, 0, 0};
	for (int i = 0; i < 3; i++)
	{
		for (;;)  // whitespace and comments
		{
			if (at >= b.n) b.fail("truncated PPM/PGM header");
			if (b.p[at] == '#')
				while (at < b.n && b.p[at] != '\n') at++;
			else if (std::isspace(b.p[at]))
				at++;
			else
				break;
		}
		if (!std::isdigit(b.p[at])) b.fail("corrupt PPM/PGM header");
		while (at < b.n && std::isdigit(b.p[at]))
		{
			v[i] = v[i] * 10 + (b.p[at++] - '0');
			if (v[i] > 0xffffffffULL) b.fail("corrupt PPM/PGM header (number too large)");
		}
	}
	if (at >= b.n || !std::isspace(b.p[at])) b.fail("truncated PPM/PGM header");
	at++;
	info.width = static_cast<uint32_t>(v[0]);
	info.height = static_cast<uint32_t>(v[1]);
	if (v[2] == 0 || v[2] > 65535) b.fail("PPM/PGM maximum value " + std::to_string(v[2]) + " is invalid");
	checkSize(b, info, maxPixels);
	const uint64_t bytes = uint64_t(info.width) * info.height * info.channels * (v[2] > 255 ? 2 : 1);
	if (b.n - at < bytes)
		b.fail(
			"truncated PPM/PGM: " + std::to_string(b.n - at) + " of " + std::to_string(bytes) +
			" pixel bytes present");
	return info;
}

TImageFileInfo checkBmp(const Bytes& b, uint64_t maxPixels)
{
	TImageFileInfo info;
	info.format = "BMP";
	const uint32_t dataOffset = b.le32(10);
	const uint32_t headerSize = b.le32(14);
	if (headerSize < 40) b.fail("unsupported BMP header (older than BITMAPINFOHEADER)");
	const int32_t w = static_cast<int32_t>(b.le32(18)), h = static_cast<int32_t>(b.le32(22));
	const uint16_t bpp = b.le16(28);
	const uint32_t compression = b.le32(30);
	if (w <= 0 || h == 0 || h == INT32_MIN) b.fail("corrupt BMP size");
	info.width = static_cast<uint32_t>(w);
	info.height = static_cast<uint32_t>(h < 0 ? -h : h);
	info.channels = bpp == 32 ? 4 : bpp == 24 ? 3 : bpp >= 8 && bpp != 16 ? 1 : 3;
	checkSize(b, info, maxPixels);
	if (compression == 0 || compression == 3)  // uncompressed (bit fields): size known
	{
		const uint64_t row = ((uint64_t(info.width) * bpp + 31) / 32) * 4;
		if (uint64_t(dataOffset) + row * info.height > b.n)
			b.fail("truncated BMP: the pixel data ends early");
	}
	return info;
}

TImageFileInfo checkTiff(const Bytes& b, uint64_t maxPixels)
{
	TImageFileInfo info;
	info.format = "TIFF";
	const bool le = b.p[0] == 'I';
	auto u16 = [&](size_t at) { return le ? b.le16(at) : b.be16(at); };
	auto u32 = [&](size_t at) { return le ? b.le32(at) : b.be32(at); };
	const uint32_t ifd = u32(4);
	const uint16_t count = u16(ifd);
	b.need(ifd + 2, size_t(count) * 12, "TIFF directory");
	auto value = [&](size_t entry, uint32_t i) -> uint64_t {
		const uint16_t type = u16(entry + 2);
		const uint32_t n = u32(entry + 4);
		const size_t size = type == 3 ? 2 : 4;
		if (i >= n) return 0;
		const size_t at = uint64_t(n) * size <= 4 ? entry + 8 + i * size : u32(entry + 8) + size_t(i) * size;
		return size == 2 ? u16(at) : u32(at);
	};
	size_t offsets = 0, counts = 0;
	uint64_t rowsPerStrip = 0xFFFFFFFFu;  // TIFF's "one strip"
	std::vector<uint16_t> seen;
	for (uint16_t k = 0; k < count; k++)
	{
		const size_t e = ifd + 2 + size_t(k) * 12;
		const uint16_t tag = u16(e);
		// libtiff keeps the first of duplicated tags; refusing them keeps
		// this check and the decoder reading the same size.
		if (std::find(seen.begin(), seen.end(), tag) != seen.end())
			b.fail("corrupt TIFF: tag " + std::to_string(tag) + " appears twice in the image directory");
		seen.push_back(tag);
		// Sizes as libtiff reads them: one value each, 8- or 16-bit samples,
		// at most 4 of them, strips (tiles make their own buffer sizes).
		if ((tag == 256 || tag == 257 || tag == 277) && u32(e + 4) != 1)
			b.fail("corrupt TIFF: tag " + std::to_string(tag) + " holds " + std::to_string(u32(e + 4)) + " values, not one");
		if (tag == 258 && value(e, 0) != 8 && value(e, 0) != 16)
			b.fail("unsupported TIFF: " + std::to_string(value(e, 0)) + "-bit samples (8 or 16 are read)");
		if (tag == 277 && (value(e, 0) < 1 || value(e, 0) > 4))
			b.fail("unsupported TIFF: " + std::to_string(value(e, 0)) + " samples per pixel (1 to 4 are read)");
		if (tag == 322 || tag == 323) b.fail("unsupported TIFF: tiled images are not read (strips are)");
		// Camera images: grey or RGB, uncompressed, LZW, Deflate or PackBits
		// (the codecs with their own buffers, JPEG-in-TIFF among them, are not read).
		if (tag == 259 && value(e, 0) != 1 && value(e, 0) != 5 && value(e, 0) != 8 && value(e, 0) != 32946 &&
			value(e, 0) != 32773)
			b.fail("unsupported TIFF compression " + std::to_string(value(e, 0)) + " (none, LZW, Deflate, PackBits are read)");
		if (tag == 262 && value(e, 0) > 2)
			b.fail("unsupported TIFF photometric interpretation " + std::to_string(value(e, 0)) + " (grey or RGB are read)");
		if (tag == 278) rowsPerStrip = value(e, 0);
		if (tag == 256) info.width = static_cast<uint32_t>(value(e, 0));
		if (tag == 257) info.height = static_cast<uint32_t>(value(e, 0));
		if (tag == 277) info.channels = static_cast<int>(value(e, 0));
		if (tag == 273) offsets = e;  // strips
		if (tag == 279) counts = e;
	}
	if (info.channels == 0) info.channels = 1;
	checkSize(b, info, maxPixels);
	// OpenCV sizes its strip buffer by RowsPerStrip, not clamped to the
	// image's height (all but the "one strip" value): bound it like an image.
	if (rowsPerStrip != 0xFFFFFFFFu && uint64_t(info.width) * rowsPerStrip > maxPixels)
		b.fail("corrupt TIFF: strips of " + std::to_string(rowsPerStrip) + " rows of " + std::to_string(info.width) +
			   " pixels exceed the " + std::to_string(maxPixels) + "-pixel limit");
	if (!offsets || !counts) b.fail("TIFF without image data offsets");
	const uint32_t n = std::min(u32(offsets + 4), u32(counts + 4));
	if (n > b.n) b.fail("corrupt TIFF strip count");
	for (uint32_t i = 0; i < n; i++)
		if (value(offsets, i) + value(counts, i) > b.n) b.fail("truncated TIFF: image data ends early");
	return info;
}
}  // namespace

TImageFileInfo checkImageBytes(const uint8_t* data, size_t size, const std::string& name, uint64_t maxPixels)
{
	const Bytes b{data, size, name};
	static const uint8_t png[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
	if (size == 0) b.fail("empty file, not an image");
	// cv::imdecode picks its decoder by signature, not by our reading of the
	// bytes: a DICOM marker at offset 128 sends the data to GDCM (which asserts
	// on corrupt input), so such data is refused before any structure check.
	if (size >= 132 && std::equal(data + 128, data + 132, "DICM"))
		b.fail("carries a DICOM signature; DICOM images are not read");
	if (size >= 8 && std::equal(png, png + 8, data)) return checkPng(b, maxPixels);
	if (size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) return checkJpeg(b, maxPixels);
	// OpenCV's PxM decoder wants whitespace after the magic; anything else
	// would be dispatched to another decoder than the one checked here.
	if (size >= 3 && data[0] == 'P' && (data[1] == '5' || data[1] == '6') && std::isspace(data[2]))
		return checkPnm(b, maxPixels);
	if (size >= 2 && data[0] == 'B' && data[1] == 'M') return checkBmp(b, maxPixels);
	if (size >= 4 && ((data[0] == 'I' && data[1] == 'I' && data[2] == 42 && data[3] == 0) ||
					  (data[0] == 'M' && data[1] == 'M' && data[2] == 0 && data[3] == 42)))
		return checkTiff(b, maxPixels);
	b.fail("not an image file of a known format (PNG, JPEG, binary PPM/PGM, BMP, TIFF)");
}

TImageFileInfo checkImageFile(const std::string& path, uint64_t maxPixels)
{
	std::error_code ec;
	if (!std::filesystem::is_regular_file(path, ec)) throw ImageFileError("'" + path + "': no such image file");
	std::ifstream f(path, std::ios::binary);
	std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
	if (f.bad()) throw ImageFileError("'" + path + "': cannot read");
	return checkImageBytes(bytes.data(), bytes.size(), path, maxPixels);
}

cv::Mat decodeImageBytes(const uint8_t* data, size_t size, const std::string& name, int flags, uint64_t maxPixels)
{
	checkImageBytes(data, size, name, maxPixels);
	cv::Mat m;
	try
	{
		m = cv::imdecode(cv::Mat(1, static_cast<int>(size), CV_8U, const_cast<uint8_t*>(data)), flags);
	}
	catch (const cv::Exception& e)
	{
		throw ImageFileError("'" + name + "': cannot decode: " + e.err);
	}
	if (m.empty()) throw ImageFileError("'" + name + "': cannot decode (corrupt image data)");
	return m;
}

cv::Mat readImageFile(const std::string& path, int flags, uint64_t maxPixels)
{
	std::error_code ec;
	if (!std::filesystem::is_regular_file(path, ec)) throw ImageFileError("'" + path + "': no such image file");
	std::ifstream f(path, std::ios::binary);
	std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
	if (f.bad()) throw ImageFileError("'" + path + "': cannot read");
	if (bytes.size() > size_t(INT32_MAX)) throw ImageFileError("'" + path + "': larger than 2 GB, not read");
	return decodeImageBytes(bytes.data(), bytes.size(), path, flags, maxPixels);
}

void checkImageWritable(const std::string& path)
{
	const std::string ext = std::filesystem::path(path).extension().string();
	bool ok = false;
	try
	{
		ok = !ext.empty() && cv::haveImageWriter(path);
	}
	catch (const cv::Exception&)
	{
		ok = false;
	}
	if (!ok)
		throw ImageFileError(
			"'" + path + "': " + (ext.empty() ? std::string("no file extension") : "unknown image format '" + ext + "'") +
			" (the extension chooses the format: .png, .jpg, .bmp, .tif, .ppm, .pgm)");
}

}  // namespace shadyloc::io
