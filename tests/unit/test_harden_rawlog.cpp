/* Rawlog reading integrity: a rawlog cut anywhere inside its last object, or a
 * gzip stream that ends without its trailer, is an error naming the file;
 * never a shorter rawlog read as complete. */
#include "../support/TestSupport.h"

#include <shadyloc/io/Rawlog.h>

#include <mrpt/img/CImage.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/core.hpp>

#include <zlib.h>

#include <malloc.h>

#include <fstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
using test::Bytes;

/** The serialised bytes of n small synthetic stereo frames, and where each
 * object starts (ends[i] = end of object i). */
Bytes serialisedFrames(int n, std::vector<size_t>& ends)
{
	mrpt::io::CMemoryStream mem;
	auto arch = mrpt::serialization::archiveFrom(mem);
	for (int i = 0; i < n; i++)
	{
		arch << *test::syntheticStereoFrame(i, 32, 24);
		ends.push_back(static_cast<size_t>(mem.getPosition()));
	}
	const auto* p = static_cast<const uint8_t*>(mem.getRawBufferData());
	return Bytes(p, p + mem.getPosition());
}

/** gzip-compresses `b`. With flushAt set, the stream is flushed (Z_FULL_FLUSH)
 * there and only the compressed bytes up to that point are returned: a gzip
 * stream cut at an object boundary, without its trailer. */
Bytes gzip(const Bytes& b, size_t flushAt = 0)
{
	z_stream z{};
	EXPECT_EQ(deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
	Bytes out(compressBound(static_cast<uLong>(b.size())) + 1024);
	z.next_out = out.data();
	z.avail_out = static_cast<uInt>(out.size());
	z.next_in = const_cast<Bytef*>(b.data());
	if (flushAt > 0)
	{
		z.avail_in = static_cast<uInt>(flushAt);
		EXPECT_EQ(deflate(&z, Z_FULL_FLUSH), Z_OK);
		out.resize(out.size() - z.avail_out);
		deflateEnd(&z);
		return out;
	}
	z.avail_in = static_cast<uInt>(b.size());
	EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
	out.resize(out.size() - z.avail_out);
	deflateEnd(&z);
	return out;
}

/** A small random colour image serialised as MRPT stores it when
 * DISABLE_JPEG_COMPRESSION is off: JPEG-compressed. */
Bytes jpegStoredImage()
{
	cv::Mat m(24, 32, CV_8UC3);
	cv::randu(m, 0, 255);
	mrpt::img::CImage img(m, mrpt::img::DEEP_COPY);
	mrpt::io::CMemoryStream mem;
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
	mrpt::serialization::archiveFrom(mem) << img;
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(true);
	const auto* p = static_cast<const uint8_t*>(mem.getRawBufferData());
	return Bytes(p, p + mem.getPosition());
}

/** Reads the whole rawlog; returns the number of objects, or throws. */
size_t readObjectCount(const std::string& path)
{
	io::RawlogReader r(path);
	size_t n = 0;
	while (r.next()) n++;
	return n;
}

/** Reading must fail with an error naming the file. */
void expectErrorNamingFile(const std::string& path, const std::string& what)
{
	try
	{
		const size_t n = readObjectCount(path);
		ADD_FAILURE() << what << ": read as complete (" << n << " objects)";
	}
	catch (const io::RawlogError& e)
	{
		EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << what << ": " << e.what();
	}
}
}  // namespace

TEST(RawlogIntegrity, WholeRawlogsReadCompletelyPlainAndGzip)
{
	const auto dir = test::tempDir("rawlog_whole");
	std::vector<size_t> ends;
	const Bytes b = serialisedFrames(4, ends);
	test::writeBytes(dir + "/plain.rawlog", b);
	test::writeBytes(dir + "/gz.rawlog", gzip(b));
	EXPECT_EQ(readObjectCount(dir + "/plain.rawlog"), 4u);
	EXPECT_EQ(readObjectCount(dir + "/gz.rawlog"), 4u);
}

TEST(RawlogIntegrity, CutAnywhereInsideTheLastObjectIsAnError)
{
	const auto dir = test::tempDir("rawlog_cut");
	std::vector<size_t> ends;
	const Bytes b = serialisedFrames(3, ends);
	const size_t lastSize = ends[2] - ends[1];
	// Every cut in the last 40 bytes (the timestamp, sensor label, poses and
	// end flag live there), and a few inside the images.
	std::vector<size_t> cuts;
	for (size_t c = 1; c <= 40; c++) cuts.push_back(c);
	for (size_t c : {lastSize / 4, lastSize / 2, lastSize - 1}) cuts.push_back(c);
	for (size_t cut : cuts)
	{
		const Bytes t(b.begin(), b.end() - static_cast<long>(cut));
		const std::string plain = dir + "/cut" + std::to_string(cut) + ".rawlog";
		const std::string gz = dir + "/cut" + std::to_string(cut) + ".gz.rawlog";
		test::writeBytes(plain, t);
		test::writeBytes(gz, gzip(t));
		expectErrorNamingFile(plain, "plain, " + std::to_string(cut) + " bytes cut");
		expectErrorNamingFile(gz, "gzip, " + std::to_string(cut) + " bytes cut");
	}
}

TEST(RawlogIntegrity, GzipStreamWithoutTrailerIsAnError)
{
	const auto dir = test::tempDir("rawlog_notrailer");
	std::vector<size_t> ends;
	const Bytes b = serialisedFrames(4, ends);
	// Cut at each object boundary: the decompressed data is whole objects,
	// only the gzip trailer (CRC-32, length) is missing.
	for (size_t k = 0; k + 1 < ends.size(); k++)
	{
		const std::string p = dir + "/notrailer" + std::to_string(k) + ".rawlog";
		test::writeBytes(p, gzip(b, ends[k]));
		expectErrorNamingFile(p, "gzip cut after object " + std::to_string(k));
	}
}

TEST(RawlogIntegrity, CompressedFileCutAnywhereNearItsEndIsAnError)
{
	// The compressed file itself cut short (a copy interrupted, a full disk):
	// the data ends inside the last object, or the trailer is missing.
	const auto dir = test::tempDir("rawlog_gzcut");
	std::vector<size_t> ends;
	const Bytes gz = gzip(serialisedFrames(3, ends));
	for (size_t cut = 1; cut <= 64; cut++)
	{
		const std::string p = dir + "/gzcut" + std::to_string(cut) + ".rawlog";
		test::writeBytes(p, Bytes(gz.begin(), gz.end() - static_cast<long>(cut)));
		expectErrorNamingFile(p, "compressed file, " + std::to_string(cut) + " bytes cut");
	}
}

TEST(RawlogIntegrity, GzipTrailerMismatchIsAnError)
{
	const auto dir = test::tempDir("rawlog_crc");
	std::vector<size_t> ends;
	const Bytes b = serialisedFrames(2, ends);
	Bytes gz = gzip(b);
	Bytes badCrc = gz, badLen = gz;
	badCrc[gz.size() - 8] ^= 0x01;	// CRC-32 of the data
	badLen[gz.size() - 4] ^= 0x01;	// length of the data mod 2^32
	test::writeBytes(dir + "/crc.rawlog", badCrc);
	test::writeBytes(dir + "/len.rawlog", badLen);
	expectErrorNamingFile(dir + "/crc.rawlog", "wrong CRC-32");
	expectErrorNamingFile(dir + "/len.rawlog", "wrong length");
}

TEST(RawlogIntegrity, AppRefusesTruncatedRawlogAndWritesNothing)
{
	const auto dir = test::tempDir("rawlog_app_cut");
	std::vector<size_t> ends;
	const Bytes b = serialisedFrames(3, ends);
	const Bytes t(b.begin(), b.end() - 5);	// inside the last object's timestamp region
	test::writeBytes(dir + "/cut.rawlog", gzip(t));
	std::string out;
	EXPECT_NE(test::runCommand(test::appPath() + " filter -q -i " + dir + "/cut.rawlog -o " + dir + "/out.rawlog", &out), 0)
		<< out;
	EXPECT_NE(out.find(dir + "/cut.rawlog"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/out.rawlog"));
}

TEST(RawlogIntegrity, ImageByteCountsAreCheckedBeforeMrptReadsThem)
{
	// A colour image stored JPEG-compressed (MRPT's format when
	// DISABLE_JPEG_COMPRESSION is off): MRPT sizes a buffer with realloc()
	// from its byte count, which no allocation bound sees.
	const auto dir = test::tempDir("rawlog_jpeg_count");
	Bytes b = jpegStoredImage();
	test::writeBytes(dir + "/ok.rawlog", b);
	EXPECT_EQ(readObjectCount(dir + "/ok.rawlog"), 1u);
	// Header: 0x91 "mrpt::img::CImage" version external hasColor w h nBytes.
	const size_t nBytesAt = 1 + 17 + 1 + 1 + 1 + 4 + 4;
	b[nBytesAt + 3] = 0xF0;	 // ~4 GB announced
	test::writeBytes(dir + "/bad.rawlog", b);
	try
	{
		readObjectCount(dir + "/bad.rawlog");
		ADD_FAILURE() << "4 GB image byte count accepted";
	}
	catch (const io::RawlogError& e)
	{
		EXPECT_NE(std::string(e.what()).find("more than remain"), std::string::npos) << e.what();
	}
}

TEST(RawlogIntegrity, CorruptJpegImageIsAnErrorNotAnExit)
{
	// MRPT decodes stored JPEG images with libjpeg's standard error manager,
	// which calls exit() on a fatal error; ours throws instead (JpegErrors.cpp).
	// Without it this test would end the test program with status 1.
	const auto dir = test::tempDir("rawlog_jpeg_corrupt");
	Bytes b = jpegStoredImage();
	const size_t jpegAt = 1 + 17 + 1 + 1 + 1 + 4 + 4 + 4;  // after nBytes
	ASSERT_EQ(b[jpegAt], 0xFF);
	ASSERT_EQ(b[jpegAt + 1], 0xD8);	 // the JPEG's start-of-image marker
	b[jpegAt + 1] = 0x00;
	const std::string path = dir + "/bad_jpeg.rawlog";
	test::writeBytes(path, b);
	try
	{
		readObjectCount(path);
		ADD_FAILURE() << "an image with a broken JPEG header read as complete";
	}
	catch (const io::RawlogError& e)
	{
		const std::string what = e.what();
		EXPECT_NE(what.find(path), std::string::npos) << what;
		EXPECT_NE(what.find("object #0"), std::string::npos) << what;
		EXPECT_NE(what.find("JPEG"), std::string::npos) << what;
	}
	// A JPEG whose data is cut (end-of-image marker and the last bytes of the
	// scan replaced by garbage) still decodes or fails with an error: never exits.
	Bytes c = jpegStoredImage();
	for (size_t i = c.size() - 40; i < c.size(); i++) c[i] = 0xFF;
	test::writeBytes(dir + "/cut_jpeg.rawlog", c);
	try
	{
		readObjectCount(dir + "/cut_jpeg.rawlog");
	}
	catch (const io::RawlogError& e)
	{
		EXPECT_NE(std::string(e.what()).find("cut_jpeg.rawlog"), std::string::npos) << e.what();
	}
}

TEST(RawlogIntegrity, AbandonedJpegDecodersAreFreed)
{
	// A JPEG header announcing a large image in a small file: libjpeg sets up
	// its decoder (megabytes for the row buffers), then the allocation bound
	// refuses MRPT's image buffer (4.3 MB) and the exception unwinds MRPT's decoder
	// without its jpeg_destroy_decompress(). The reader frees it (JpegErrors.cpp):
	// 20 such reads must not grow the heap by their ~2 MB each. (Under ASan,
	// whose allocator mallinfo2 does not see, LeakSanitizer checks the same.)
	const auto dir = test::tempDir("rawlog_jpeg_orphan");
	Bytes b = jpegStoredImage();
	size_t sof = 0;
	for (size_t i = 0; i + 9 < b.size() && !sof; i++)
		if (b[i] == 0xFF && b[i + 1] == 0xC0) sof = i;	// baseline start-of-frame
	ASSERT_GT(sof, 0u);
	b[sof + 7] = 0xEA, b[sof + 8] = 0x60;  // width 60000 (height stays 24)
	const std::string path = dir + "/huge_jpeg.rawlog";
	test::writeBytes(path, b);
	const auto heapInUse = [] { return mallinfo2().uordblks; };
	std::string first;
	const size_t before = heapInUse();
	for (int k = 0; k < 20; k++)
	{
		try
		{
			readObjectCount(path);
			ADD_FAILURE() << "a 60000x24 JPEG in a " << b.size() << "-byte file read as complete";
		}
		catch (const io::RawlogError& e)
		{
			if (first.empty()) first = e.what();
		}
	}
	const size_t after = heapInUse();
	EXPECT_NE(first.find(path), std::string::npos) << first;
	EXPECT_LT(after, before + 4 * 1024 * 1024) << "heap grew by " << (after - before) << " bytes over 20 reads";
}
