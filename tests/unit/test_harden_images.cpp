/* Image files: a truncated JPEG or PNG is an error naming the file (OpenCV
 * alone fills the missing rows grey); absurd dimensions are refused before
 * decoding; unknown formats get a clear message. */
#include "../support/TestSupport.h"

#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/Rawlog.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <array>
#include <fstream>
#include <sstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** A textured colour image (so that JPEG has real entropy-coded data). */
cv::Mat texture(int w, int h)
{
	cv::Mat m(h, w, CV_8UC3);
	cv::randu(m, 0, 255);
	return m;
}

/** Writes `name` (format by extension) and a copy cut to `fraction` of its size. */
std::string truncatedCopy(const std::string& dir, const std::string& name, double fraction)
{
	const std::string whole = dir + "/whole_" + name, cut = dir + "/cut_" + name;
	EXPECT_TRUE(cv::imwrite(whole, texture(64, 48)));
	const std::string b = test::fileContents(whole);
	test::writeFileContents(cut, b.substr(0, static_cast<size_t>(b.size() * fraction)));
	return cut;
}
}  // namespace

TEST(ImageFiles, TruncatedJpegAndPngAreErrorsNamingTheFile)
{
	const auto dir = test::tempDir("img_trunc");
	for (const char* name : {"a.jpg", "a.png"})
		for (double fraction : {0.5, 0.9, 0.99})
		{
			const std::string cut = truncatedCopy(dir, name, fraction);
			std::string out;
			EXPECT_NE(test::runCommand(test::appPath() + " image " + cut + " " + dir + "/out.png", &out), 0)
				<< name << " cut to " << fraction << ": accepted\n" << out;
			EXPECT_NE(out.find(cut), std::string::npos) << out;
			EXPECT_FALSE(fs::exists(dir + "/out.png"));
			fs::remove(dir + "/out.png");
		}
}

TEST(ImageFiles, ImportRefusesTruncatedImages)
{
	for (const char* ext : {".png", ".jpg"})
	{
	const auto dir = test::tempDir("img_trunc_import");
	fs::create_directories(dir + "/L");
	fs::create_directories(dir + "/R");
	for (int i = 0; i < 2; i++)
	{
		const std::string n = "/" + std::to_string(i) + ext;
		ASSERT_TRUE(cv::imwrite(dir + "/L" + n, texture(64, 48)));
		ASSERT_TRUE(cv::imwrite(dir + "/R" + n, texture(64, 48)));
	}
	const std::string victim = dir + "/R/1" + ext;
	const std::string b = test::fileContents(victim);
	test::writeFileContents(victim, b.substr(0, b.size() * 3 / 4));
	std::ofstream(dir + "/calib.ini") << "[left]\nfx_px = 50\nfy_px = 50\ncx_px = 32\ncy_px = 24\n"
										 "[stereo]\nbaseline_m = 0.1\nwidth_px = 64\nheight_px = 48\n";
	std::string out;
	EXPECT_NE(test::runCommand(test::appPath() + " import folder -q --left " + dir + "/L --right " + dir + "/R --calib " +
								   dir + "/calib.ini --rate 10 -o " + dir + "/out.rawlog",
				  &out),
		0)
		<< out;
	EXPECT_NE(out.find(victim), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/out.rawlog"));
	}
}

TEST(ImageFiles, TruncatedExternalImageInARawlogIsAnError)
{
	for (const std::string& ext : std::vector<std::string>{".png", ".jpg"})
	{
	const auto dir = test::tempDir("img_trunc_external");
	{
		io::RawlogWriter w(dir + "/r.rawlog", true);
		for (int i = 0; i < 2; i++)
		{
			auto obs = test::syntheticStereoFrame(i, 64, 48);
			w.externalise(obs->imageLeft, "L" + std::to_string(i) + ext);
			w.externalise(obs->imageRight, "R" + std::to_string(i) + ext);
			w.write(*obs);
		}
		w.commit();
	}
	const std::string victim = dir + "/r_Images/L1" + ext;
	const std::string b = test::fileContents(victim);
	test::writeFileContents(victim, b.substr(0, b.size() * 2 / 3));
	std::string out;
	EXPECT_NE(test::runCommand(test::appPath() + " filter -q -i " + dir + "/r.rawlog -o " + dir + "/f.rawlog", &out), 0)
		<< out;
	EXPECT_NE(out.find("L1" + ext), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/f.rawlog"));
	}
}

TEST(ImageFiles, BytesOpenCVWouldSendToAnotherDecoderAreRefused)
{
	// Found by fuzz_image: "P6" without whitespace is no PPM to OpenCV, and a
	// DICOM marker at offset 128 then routes the bytes to GDCM, which aborts.
	std::string bytes = "P61\n6 1\n 3";
	bytes.resize(128, '\0');
	bytes += "DICM";
	bytes.resize(160, '\x05');
	const auto* p = reinterpret_cast<const uint8_t*>(bytes.data());
	EXPECT_THROW(io::decodeImageBytes(p, bytes.size(), "crash.bin", cv::IMREAD_UNCHANGED, 1u << 22), io::ImageFileError);

	// A well-formed PPM that happens to carry the marker is refused too: the
	// dispatch, not our header check, would decide which decoder reads it.
	std::string ppm = "P6\n8 8\n255\n";
	ppm.resize(ppm.size() + 8 * 8 * 3, '\x40');
	std::copy_n("DICM", 4, ppm.begin() + 128);
	const auto* q = reinterpret_cast<const uint8_t*>(ppm.data());
	try
	{
		io::decodeImageBytes(q, ppm.size(), "marked.ppm", cv::IMREAD_UNCHANGED, 1u << 22);
		ADD_FAILURE() << "a PPM carrying a DICOM marker was decoded";
	}
	catch (const io::ImageFileError& e)
	{
		EXPECT_NE(std::string(e.what()).find("marked.ppm"), std::string::npos) << e.what();
	}

	// Without the marker the same PPM decodes.
	std::copy_n("\x40\x40\x40\x40", 4, ppm.begin() + 128);
	EXPECT_EQ(io::decodeImageBytes(q, ppm.size(), "plain.ppm", cv::IMREAD_UNCHANGED, 1u << 22).cols, 8);
}

namespace
{
/** A little-endian TIFF header and one image directory of LONG entries. */
std::string tiffWith(const std::vector<std::array<uint32_t, 2>>& tags)
{
	std::string t = "II*";
	t += '\0';
	const auto le16 = [&](uint16_t v) { t += char(v & 0xff); t += char(v >> 8); };
	const auto le32 = [&](uint32_t v) { for (int i = 0; i < 4; i++) t += char((v >> (8 * i)) & 0xff); };
	le32(8);
	le16(static_cast<uint16_t>(tags.size()));
	for (const auto& e : tags)
	{
		le16(static_cast<uint16_t>(e[0]));
		le16(4);
		le32(1);
		le32(e[1]);
	}
	le32(0);
	return t;
}
}  // namespace

TEST(ImageFiles, TiffStripsLargerThanTheImageLimitAreRefused)
{
	// Found by fuzz_image: OpenCV sized its strip buffer by RowsPerStrip
	// (16396 rows of 15632 pixels: 1 GB) for an image 12 rows high.
	const std::string t = tiffWith({{256, 15632}, {257, 12}, {277, 3}, {278, 16396}, {273, 0}, {279, 1}});
	try
	{
		io::decodeImageBytes(reinterpret_cast<const uint8_t*>(t.data()), t.size(), "strips.tif", cv::IMREAD_UNCHANGED, 1u << 22);
		ADD_FAILURE() << "a TIFF with 16396-row strips was decoded";
	}
	catch (const io::ImageFileError& e)
	{
		EXPECT_NE(std::string(e.what()).find("strips of 16396 rows"), std::string::npos) << e.what();
	}
}

TEST(ImageFiles, TiffWithADuplicatedSizeTagIsRefused)
{
	// Found by fuzz_image: a second ImageWidth entry made this check read a
	// small image while libtiff (keeping the first) allocated 480 MB.
	std::string t = "II*";
	t += '\0';
	const auto le16 = [&](uint16_t v) { t += char(v & 0xff); t += char(v >> 8); };
	const auto le32 = [&](uint32_t v) { for (int i = 0; i < 4; i++) t += char((v >> (8 * i)) & 0xff); };
	le32(8);  // the image directory follows the header
	const std::vector<std::array<uint32_t, 4>> entries = {
		{256, 4, 1, 15632}, {257, 4, 1, 10240}, {256, 4, 1, 8}, {273, 4, 1, 0}, {279, 4, 1, 1}};
	le16(static_cast<uint16_t>(entries.size()));
	for (const auto& e : entries)
	{
		le16(static_cast<uint16_t>(e[0]));
		le16(static_cast<uint16_t>(e[1]));
		le32(e[2]);
		le32(e[3]);
	}
	le32(0);
	const auto* p = reinterpret_cast<const uint8_t*>(t.data());
	try
	{
		io::decodeImageBytes(p, t.size(), "dup.tif", cv::IMREAD_UNCHANGED, 1u << 22);
		ADD_FAILURE() << "a TIFF with two ImageWidth tags was decoded";
	}
	catch (const io::ImageFileError& e)
	{
		EXPECT_NE(std::string(e.what()).find("appears twice"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("dup.tif"), std::string::npos) << e.what();
	}
}
