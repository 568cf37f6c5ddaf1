/* ShadyLoc tests: folder-of-images import. */
#include <shadyloc/datasets/Folder.h>
#include <shadyloc/io/Rawlog.h>

#include "../support/TestSupport.h"

#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <functional>

using namespace shadyloc::datasets;
namespace fs = std::filesystem;

namespace
{
/** L/ and R/ with n random colour PNGs named differently on each side
 * (pairing is by sorted order, not by name), and a calibration file. */
void makeFolders(const std::string& dir, int n, int w = 48, int h = 32)
{
	fs::create_directories(dir + "/L");
	fs::create_directories(dir + "/R");
	cv::RNG rng(5);
	for (int i = 0; i < n; i++)
	{
		cv::Mat a(h, w, CV_8UC3), b(h, w, CV_8UC3);
		rng.fill(a, cv::RNG::UNIFORM, 0, 256);
		rng.fill(b, cv::RNG::UNIFORM, 0, 256);
		cv::imwrite(dir + "/L/left_" + std::to_string(100 + i) + ".png", a);
		cv::imwrite(dir + "/R/right_" + std::to_string(100 + i) + ".png", b);
	}
	std::ofstream f(dir + "/calib.ini");
	f << "[left]\nfx_px=400\nfy_px=401\ncx_px=24.5\ncy_px=16.25\n[right]\ncx_px=26\n[stereo]\nbaseline_m=0.25\n"
	  << "width_px=" << w << "\nheight_px=" << h << "\n";
}

}  // namespace

TEST(DatasetsFolder, ImportsPairsWithCalibrationAndRate)
{
	const std::string dir = shadyloc::test::tempDir("folder_ok");
	makeFolders(dir, 4);
	FolderImporter imp;
	imp.setMinLoggingLevel(mrpt::system::LVL_WARN);
	imp.rateHz = 20;
	imp.startTime = 1.6e9;
	imp.options.sensorLabel = "STEREO";
	const auto res = imp.run(dir + "/L", dir + "/R", dir + "/calib.ini", dir + "/out.rawlog");
	EXPECT_EQ(res.frames, 4u);
	const auto obs = shadyloc::test::readStereoFrames(dir + "/out.rawlog");
	ASSERT_EQ(obs.size(), 4u);
	for (int i = 0; i < 4; i++)
	{
		const auto& o = *obs[i];
		EXPECT_EQ(o.sensorLabel, "STEREO");
		// 1.6e9 s + i / 20 Hz, to the 100 ns clock tick (plus the double's
		// 2.4e-7 s spacing at 1.6e9): 5e-7.
		EXPECT_NEAR(mrpt::Clock::toDouble(o.timestamp), 1.6e9 + i * 0.05, 5e-7);
		EXPECT_EQ(o.leftCamera.fx(), 400.0);
		EXPECT_EQ(o.leftCamera.fy(), 401.0);
		EXPECT_EQ(o.rightCamera.fy(), 401.0);  // from [left]: key absent in [right]
		EXPECT_EQ(o.leftCamera.cx(), 24.5);
		EXPECT_EQ(o.rightCamera.cx(), 26.0);
		EXPECT_EQ(o.rightCameraPose.x(), 0.25);
		cv::Mat d;
		cv::absdiff(o.imageRight.asCvMatRef(), cv::imread(dir + "/R/right_" + std::to_string(100 + i) + ".png"), d);
		EXPECT_EQ(cv::countNonZero(d.reshape(1)), 0) << "pair " << i;
	}

	// --times through the app, and --max-frames.
	{
		std::ofstream f(dir + "/times.txt");
		f << "# t\n10.0\n10.5\n11.25\n12.0\n";
	}
	std::string text;
	const int rc = shadyloc::test::runCommand(
		shadyloc::test::appPath() + " import folder --left " + dir + "/L --right " + dir + "/R --calib " +
			dir + "/calib.ini --times " + dir + "/times.txt --max-frames 3 -o " + dir + "/t.rawlog",
		&text);
	ASSERT_EQ(rc, 0) << text;
	const auto t = shadyloc::test::readStereoFrames(dir + "/t.rawlog");
	ASSERT_EQ(t.size(), 3u);
	EXPECT_NEAR(mrpt::Clock::toDouble(t[2]->timestamp), 11.25, 1e-9);
}

TEST(DatasetsFolder, ExampleCalibrationParses)
{
	const auto c = TFolderCalib::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/folder_calib_example.ini");
	EXPECT_EQ(c.fx_l, 713.189);
	EXPECT_EQ(c.cx_r, 387.361);
	EXPECT_EQ(c.baseline_m, 0.178089);
	EXPECT_EQ(c.width, 707u);
	EXPECT_EQ(c.height, 481u);
}

TEST(DatasetsFolder, BadInputNamesTheCulpritAndLeavesNothing)
{
	const std::string dir = shadyloc::test::tempDir("folder_bad");
	makeFolders(dir, 3);
	const std::string out = dir + "/out.rawlog";
	auto expectError = [&](const std::string& needle, const std::function<void(FolderImporter&)>& setup) {
		FolderImporter imp;
		imp.setMinLoggingLevel(mrpt::system::LVL_ERROR);
		imp.rateHz = 10;
		setup(imp);
		try
		{
			imp.run(dir + "/L", dir + "/R", dir + "/calib.ini", out);
			ADD_FAILURE() << "expected an error naming '" << needle << "'";
		}
		catch (const DatasetError& e)
		{
			EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
		}
		EXPECT_FALSE(fs::exists(out));
		EXPECT_FALSE(fs::exists(dir + "/.out.rawlog.tmp"));
	};
	// Timestamps file with the wrong count.
	{
		std::ofstream f(dir + "/times.txt");
		f << "1\n2\n";
	}
	expectError("times.txt' has 2 timestamps", [&](FolderImporter& i) { i.timesFile = dir + "/times.txt"; });
	// Neither rate nor times.
	expectError("rate", [&](FolderImporter& i) { i.rateHz = 0; });
	// Image size differs from the calibration, at the last pair.
	cv::imwrite(dir + "/L/left_102.png", cv::Mat(33, 48, CV_8UC3, cv::Scalar::all(7)));
	expectError("frame 2 ('left_102.png'", [](FolderImporter&) {});
	// Missing calibration key.
	{
		std::ofstream f(dir + "/calib.ini");
		f << "[left]\nfx_px=400\nfy_px=400\ncx_px=24\ncy_px=16\n[stereo]\nwidth_px=48\nheight_px=32\n";
	}
	expectError("[stereo] baseline_m: missing", [](FolderImporter&) {});
	makeFolders(dir, 3);  // good again
	// Missing right folder, and mismatched counts.
	fs::rename(dir + "/R", dir + "/R2");
	expectError(dir + "/R'", [](FolderImporter&) {});
	fs::create_directories(dir + "/R");
	fs::copy_file(dir + "/R2/right_100.png", dir + "/R/right_100.png");
	expectError("R' has 1", [](FolderImporter&) {});
}
