/* ShadyLoc tests: Middlebury 2014 scene import. */
#include <shadyloc/datasets/Middlebury.h>
#include <shadyloc/io/Rawlog.h>

#include "../support/TestSupport.h"

#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/imgcodecs.hpp>

#include <fstream>

using namespace shadyloc::datasets;
namespace fs = std::filesystem;

namespace
{
mrpt::obs::CObservationStereoImages::Ptr readOnlyFrame(const std::string& rawlog)
{
	shadyloc::io::RawlogReader r(rawlog);
	auto obj = r.next();
	EXPECT_TRUE(obj);
	EXPECT_FALSE(r.next()) << "more than one object";
	auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(obj);
	EXPECT_TRUE(obs);
	return obs;
}
}  // namespace

TEST(DatasetsMiddlebury, PianoCalibrationSurvivesExactly)
{
	SHADYLOC_REQUIRE_SHARED_DATA("middlebury/Piano");
	const std::string scene = shadyloc::test::sharedDataDir() + "/middlebury/Piano";
	const std::string dir = shadyloc::test::tempDir("middlebury_piano");
	const std::string out = dir + "/piano.rawlog";

	MiddleburyImporter imp;
	imp.setMinLoggingLevel(mrpt::system::LVL_WARN);
	const auto res = imp.run(scene, out);
	EXPECT_EQ(res.frames, 1u);
	EXPECT_TRUE(res.groundTruthPath.empty());

	const auto obs = readOnlyFrame(out);
	ASSERT_TRUE(obs);
	// Piano/calib.txt: cam0=[713.189 0 356.021; 0 713.189 238.263; 0 0 1],
	// cam1 cx = 387.361, doffs=31.34, baseline=178.089 (mm), 707 x 481.
	// Values are copied, not computed, so they must come back exactly (==);
	// doffs and the baseline in metres are a subtraction and a division by
	// 1000 away, hence 1e-12.
	EXPECT_EQ(obs->sensorLabel, "CAMERA");
	EXPECT_EQ(obs->leftCamera.fx(), 713.189);
	EXPECT_EQ(obs->leftCamera.fy(), 713.189);
	EXPECT_EQ(obs->rightCamera.fx(), 713.189);
	EXPECT_EQ(obs->rightCamera.fy(), 713.189);
	EXPECT_EQ(obs->leftCamera.cx(), 356.021);
	EXPECT_EQ(obs->leftCamera.cy(), 238.263);
	EXPECT_EQ(obs->rightCamera.cx(), 387.361);
	EXPECT_EQ(obs->rightCamera.cy(), 238.263);
	EXPECT_NEAR(obs->rightCamera.cx() - obs->leftCamera.cx(), 31.34, 1e-12);	// doffs
	EXPECT_NEAR(obs->rightCameraPose.x() * 1000.0, 178.089, 1e-12);			// baseline [mm]
	EXPECT_EQ(obs->rightCameraPose.y(), 0.0);
	EXPECT_EQ(obs->rightCameraPose.z(), 0.0);
	EXPECT_EQ(obs->rightCameraPose.quat().r(), 1.0);
	EXPECT_EQ(obs->leftCamera.ncols, 707u);
	EXPECT_EQ(obs->leftCamera.nrows, 481u);
	EXPECT_EQ(obs->rightCamera.ncols, 707u);
	for (int k = 0; k < 8; k++) EXPECT_EQ(obs->leftCamera.dist[k], 0.0);

	// Images: the decoded PNGs, BGR, pixel for pixel.
	cv::Mat d;
	cv::absdiff(obs->imageLeft.asCvMatRef(), cv::imread(scene + "/im0.png"), d);
	EXPECT_EQ(cv::countNonZero(d.reshape(1)), 0);
	cv::absdiff(obs->imageRight.asCvMatRef(), cv::imread(scene + "/im1.png"), d);
	EXPECT_EQ(cv::countNonZero(d.reshape(1)), 0);

	// The parser agrees with the observation and reads ndisp too.
	const auto c = TMiddleburyCalib::FromFile(scene + "/calib.txt");
	EXPECT_EQ(c.doffs, 31.34);
	EXPECT_EQ(c.baseline_mm, 178.089);
	EXPECT_EQ(c.ndisp, 65);
}

TEST(DatasetsMiddlebury, BadSceneNamesTheCulprit)
{
	const std::string dir = shadyloc::test::tempDir("middlebury_bad");
	const std::string out = dir + "/out.rawlog";
	fs::create_directories(dir + "/S");
	cv::imwrite(dir + "/S/im0.png", cv::Mat(20, 30, CV_8UC3, cv::Scalar(10, 20, 30)));
	cv::imwrite(dir + "/S/im1.png", cv::Mat(20, 30, CV_8UC3, cv::Scalar(10, 20, 30)));
	auto writeCalib = [&](const std::string& extra, bool withBaseline) {
		std::ofstream f(dir + "/S/calib.txt");
		f << "cam0=[100 0 15; 0 100 10; 0 0 1]\ncam1=[100 0 17; 0 100 10; 0 0 1]\ndoffs=2\n"
		  << (withBaseline ? "baseline=120.5\n" : "") << extra;
	};
	auto expectError = [&](const std::string& needle) {
		MiddleburyImporter imp;
		imp.setMinLoggingLevel(mrpt::system::LVL_ERROR);
		try
		{
			imp.run(dir + "/S", out);
			ADD_FAILURE() << "expected an error naming '" << needle << "'";
		}
		catch (const DatasetError& e)
		{
			EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
		}
		EXPECT_FALSE(fs::exists(out));
	};
	writeCalib("width=30\nheight=20\n", false);
	expectError("missing key 'baseline='");
	writeCalib("width=31\nheight=20\n", true);
	expectError("im0.png' is 30x20");
	writeCalib("width=30\nheight=20\n", true);
	{
		MiddleburyImporter imp;
		imp.setMinLoggingLevel(mrpt::system::LVL_ERROR);
		const auto r = imp.run(dir + "/S", out);
		EXPECT_NEAR(r.rightCameraPose.x(), 0.1205, 1e-15);
		EXPECT_EQ(r.rightCamera.cx(), 17.0);
	}
	fs::remove(out);
	// An unreadable right image is named.
	{
		std::ofstream f(dir + "/S/im1.png", std::ios::trunc);
		f << "garbage";
	}
	expectError(dir + "/S/im1.png");
}
