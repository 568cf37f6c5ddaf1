/* The `shadyloc` command line: dispatch, and `shadyloc image`. */
#include "../support/TestSupport.h"

#include <shadyloc/image/ColourTransforms.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fstream>

using namespace shadyloc::test;
namespace fs = std::filesystem;

TEST(App, UsageAndUnknownCommand)
{
	std::string out;
	EXPECT_EQ(runCommand(appPath() + " --help", &out), 0);
	EXPECT_NE(out.find("filter"), std::string::npos);
	EXPECT_NE(out.find("image"), std::string::npos);
	EXPECT_NE(runCommand(appPath() + " frobnicate", &out), 0);
	EXPECT_NE(out.find("unknown command 'frobnicate'"), std::string::npos);
	EXPECT_NE(runCommand(appPath(), &out), 0);
}

TEST(AppImage, InvariantAndMonoMatchTheLibrary)
{
	const auto dir = tempDir("app_image");
	cv::Mat img(60, 80, CV_8UC3);
	cv::randu(img, 0, 255);
	ASSERT_TRUE(cv::imwrite(dir + "/in.png", img));
	std::string out;
	ASSERT_EQ(runCommand(appPath() + " image " + dir + "/in.png " + dir + "/inv.png --channel invariant --linearise srgb", &out), 0) << out;
	ASSERT_EQ(runCommand(appPath() + " image " + dir + "/in.png " + dir + "/mono.png --channel mono", &out), 0) << out;
	auto p = shadyloc::image::InvariantParams::FromAlphaBeta(0.48, 0.5065);
	p.linearisation = shadyloc::image::Linearisation::SRGB;
	cv::Mat expectInv, expectMono;
	shadyloc::image::InvariantTransform(p).apply(img, expectInv);
	shadyloc::image::toMonochrome(img, expectMono, shadyloc::image::ChannelOrder::BGR);
	EXPECT_EQ(cv::norm(cv::imread(dir + "/inv.png", cv::IMREAD_UNCHANGED), expectInv, cv::NORM_INF), 0);
	EXPECT_EQ(cv::norm(cv::imread(dir + "/mono.png", cv::IMREAD_UNCHANGED), expectMono, cv::NORM_INF), 0);

	// Wavelength form: alpha from the peaks, beta = 1 - alpha.
	ASSERT_EQ(runCommand(appPath() + " image " + dir + "/in.png " + dir + "/wl.png --wavelengths 470,540,620", &out), 0) << out;
	EXPECT_NE(out.find("alpha=0.4641975"), std::string::npos) << out;
}

// --config takes the whole transform from a filter section, e.g. the
// [invariant] that calibrate-alpha writes, compressed tails included.
TEST(AppImage, ConfigSectionGivesTheCalibratedTransform)
{
	const auto dir = tempDir("app_image_config");
	cv::Mat img(60, 80, CV_8UC3);
	cv::randu(img, 0, 255);
	ASSERT_TRUE(cv::imwrite(dir + "/in.png", img));
	{
		std::ofstream f(dir + "/cam.ini");
		f << "[invariant]\nclass = shadyloc::CFilterInvariant\nalpha = 0.43\nbeta = 0.57\nlinearisation = srgb\n"
			 "scale = 171.4\noffset = 0.8\nknee_low = 34\nknee_high = 244\ntail_slope_low = 0.27\n"
			 "tail_slope_high = 0.5\n[typo]\nalpha = 0.4\nscael = 2\n";
	}
	std::string out;
	ASSERT_EQ(runCommand(appPath() + " image " + dir + "/in.png " + dir + "/inv.png -c " + dir + "/cam.ini", &out), 0)
		<< out;
	auto p = shadyloc::image::InvariantParams::FromAlphaBeta(0.43, 0.57);
	p.linearisation = shadyloc::image::Linearisation::SRGB;
	p.scale = 171.4, p.offset = 0.8, p.knee_low = 34, p.knee_high = 244, p.tail_slope_low = 0.27,
	p.tail_slope_high = 0.5;
	cv::Mat expect;
	shadyloc::image::InvariantTransform(p).apply(img, expect);
	EXPECT_EQ(cv::norm(cv::imread(dir + "/inv.png", cv::IMREAD_UNCHANGED), expect, cv::NORM_INF), 0);
	EXPECT_NE(out.find("tail_slope_low=0.27"), std::string::npos) << out;

	struct Case
	{
		std::string args, expect;
	};
	for (const auto& c : std::vector<Case>{
			 {"-c " + dir + "/cam.ini --alpha 0.4", "--config gives the whole transform"},
			 {"-c " + dir + "/none.ini", "no such file"},
			 {"-c " + dir + "/cam.ini --section other", "no section [other]"},
			 {"-c " + dir + "/cam.ini --section typo", "scael"},
			 {"--section invariant", "--section needs --config"}})
	{
		const int rc = runCommand(appPath() + " image " + dir + "/in.png " + dir + "/o.png " + c.args, &out);
		EXPECT_NE(rc, 0) << c.args;
		EXPECT_NE(out.find(c.expect), std::string::npos) << c.args << ": " << out;
		EXPECT_FALSE(fs::exists(dir + "/o.png")) << c.args;
	}
}

TEST(AppImage, BadInputClearErrorNoOutput)
{
	const auto dir = tempDir("app_image_bad");
	cv::Mat grey(20, 20, CV_8UC1, cv::Scalar(50));
	ASSERT_TRUE(cv::imwrite(dir + "/grey.png", grey));
	{
		std::ofstream f(dir + "/broken.png");
		f << "not a png";
	}
	struct Case
	{
		std::string args, expect;
	};
	for (const auto& c : std::vector<Case>{
			 {dir + "/nope.png " + dir + "/o.png", "no such image file"},
			 {dir + "/broken.png " + dir + "/o.png", "cannot read image"},
			 {dir + "/grey.png " + dir + "/o.png --channel invariant", "needs a colour image"},
			 {dir + "/grey.png " + dir + "/o.png --channel mono --wavelengths 600,500,400", ""},
			 {dir + "/grey.png " + dir + "/o.png --channel sepia", "sepia"}})
	{
		std::string out;
		const int rc = runCommand(appPath() + " image " + c.args, &out);
		if (c.expect.empty())
		{
			// mono ignores the invariant options: a valid run.
			EXPECT_EQ(rc, 0) << out;
			fs::remove(dir + "/o.png");
			continue;
		}
		EXPECT_NE(rc, 0) << c.args;
		EXPECT_NE(out.find(c.expect), std::string::npos) << out;
		EXPECT_FALSE(fs::exists(dir + "/o.png")) << c.args;
	}
}
