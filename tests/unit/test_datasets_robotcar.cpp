/* ShadyLoc tests: Oxford RobotCar layout -> rawlog, on a replica the test
 * builds from the synthetic corridor (raw GBRG mosaics, an SDK-style camera
 * model and look-up table, stereo.timestamps, extrinsics and gps/ins.csv
 * from the known poses), and bad input. */
#include <shadyloc/datasets/RobotCar.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/StereoFrameSource.h>
#include <shadyloc/io/Tum.h>

#include "../support/Sequences.h"
#include "../support/TestSupport.h"

#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>

using namespace shadyloc::datasets;
namespace fs = std::filesystem;

namespace
{
constexpr int kRobotCarFrames = 6;
constexpr double kRobotCarSpeed = 0.1;	// m per frame
constexpr int64_t kT0 = 1418381798000000;  // [us], a RobotCar-like Unix time
constexpr int64_t kFramePeriod = 100000;  // [us]: frame k of the corridor is 0.1 k s

// Extrinsics written for the replica (not the SDK's values; all non-zero so
// that a wrong composition order shows).
const double kStereoXyzrpy[6] = {0.02, -0.01, 0.03, 0.01, -0.02, 0.015};
const double kInsXyzrpy[6] = {-1.7132, 0.1181, 1.1948, -0.0125, 0.04, 0.005};

// Mean |error| [grey levels] of bilinear demosaicing on the corridor's
// frames, measured 6.9-7.2 (a Gaussian-blurred frame, sigma 1 px: 2.0); a
// one-pixel shift of the output gives 12.8-13.9 (measured).
constexpr double kDemosaicError = 8.0, kMisregistered = 11.0;
const cv::Rect kInner(2, 2, 300, 200);	// compared with shifted windows

const shadyloc::test::TStereoSequence& corridor() { return shadyloc::test::corridorSequence(kRobotCarFrames, kRobotCarSpeed); }

/** The corridor's camera pose at a fractional frame number (examplePose's
 * formula, which takes whole frames only), for INS rows between frames. */
Eigen::Isometry3d leftPoseAt(double k)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.translation() = Eigen::Vector3d(0.4 * std::sin(0.09 * k), 0.15 * std::sin(0.06 * k + 0.5), kRobotCarSpeed * k);
	const double yaw = 6.0 * M_PI / 180 * std::sin(0.07 * k), pitch = 2.0 * M_PI / 180 * std::sin(0.05 * k);
	T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()))
					 .toRotationMatrix();
	return T;
}

/** The lens image frame (x right, y down, z forward) in the camera's base
 * frame (x forward, y right, z down), lens at y = offset. */
Eigen::Isometry3d G_camera_image(double offset)
{
	Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
	G.linear() << 0, 0, 1, 1, 0, 0, 0, 1, 0;
	G.translation() = Eigen::Vector3d(0, offset, 0);
	return G;
}

/** The INS frame -> left image frame, as the importer must compose it. */
Eigen::Isometry3d T_ins_left()
{
	return (robotcarTransform(kStereoXyzrpy) * robotcarTransform(kInsXyzrpy)).inverse() * G_camera_image(0);
}

/** A BGR image sampled as a GBRG mosaic (row 0: G B, row 1: R G). */
cv::Mat mosaicGBRG(const cv::Mat& bgr)
{
	cv::Mat raw(bgr.size(), CV_8UC1);
	for (int r = 0; r < bgr.rows; r++)
		for (int c = 0; c < bgr.cols; c++)
		{
			const cv::Vec3b p = bgr.at<cv::Vec3b>(r, c);
			const int ch = (r % 2 == 0) ? (c % 2 == 0 ? 1 : 0) : (c % 2 == 0 ? 2 : 1);
			raw.at<uint8_t>(r, c) = p[ch];
		}
	return raw;
}

void writeModel(
	const std::string& dir, const std::string& name, const shadyloc::geometry::TStereoCalib& c, double cx,
	const Eigen::Isometry3d& G)
{
	std::ofstream f(dir + "/" + name + ".txt");
	char b[256];
	std::snprintf(b, sizeof b, "%.6f %.6f %.6f %.6f\n", c.fx, c.fy, cx, c.cy);
	f << b;
	const Eigen::Matrix4d M = G.matrix();
	for (int r = 0; r < 4; r++)
	{
		std::snprintf(b, sizeof b, "%.6f %.6f %.6f %.6f\n", M(r, 0), M(r, 1), M(r, 2), M(r, 3));
		f << b;
	}
}

/** An SDK-style LUT for w x h images: rectified pixel (r, c) samples the raw
 * image at (c + du, r + dv). */
void writeLut(const std::string& dir, const std::string& name, int w, int h, double du, double dv)
{
	std::vector<double> lut(2 * size_t(w) * h);
	const size_t n = size_t(w) * h;
	for (int r = 0; r < h; r++)
		for (int c = 0; c < w; c++)
		{
			lut[size_t(r) * w + c] = c + du;
			lut[n + size_t(r) * w + c] = r + dv;
		}
	std::ofstream f(dir + "/" + name + "_distortion_lut.bin", std::ios::binary);
	f.write(reinterpret_cast<const char*>(lut.data()), std::streamsize(lut.size() * sizeof(double)));
}

/** Both models of a rectified pair with calibration c, and their LUTs. */
void writeModels(const std::string& dir, const shadyloc::geometry::TStereoCalib& c, int w, int h, double du, double dv)
{
	fs::create_directories(dir);
	writeModel(dir, "stereo_wide_left", c, c.cx, G_camera_image(0));
	writeModel(dir, "stereo_wide_right", c, c.cxR, G_camera_image(c.baseline));
	for (const char* name : {"stereo_wide_left", "stereo_wide_right"}) writeLut(dir, name, w, h, du, dv);
}

void writeExtrinsics(const std::string& dir)
{
	fs::create_directories(dir);
	auto line = [](const double v[6]) {
		char b[200];
		std::snprintf(b, sizeof b, "%.6f %.6f %.6f %.6f %.6f %.6f\n", v[0], v[1], v[2], v[3], v[4], v[5]);
		return std::string(b);
	};
	std::ofstream(dir + "/stereo.txt") << line(kStereoXyzrpy);
	std::ofstream(dir + "/ins.txt") << line(kInsXyzrpy);
}

/** gps/ins.csv: one row per (time, T_world_left), as the INS would see it. */
void writeIns(const std::string& path, const std::vector<std::pair<int64_t, Eigen::Isometry3d>>& poses)
{
	std::ofstream f(path);
	f << "timestamp,ins_status,latitude,longitude,altitude,northing,easting,down,utm_zone,"
		 "velocity_north,velocity_east,velocity_down,roll,pitch,yaw\n";
	const Eigen::Isometry3d T_left_ins = T_ins_left().inverse();
	for (const auto& [t, T_world_left] : poses)
	{
		const Eigen::Isometry3d T = T_world_left * T_left_ins;
		const Eigen::Vector3d ypr = T.linear().eulerAngles(2, 1, 0);  // R = Rz(yaw) Ry(pitch) Rx(roll)
		const Eigen::Vector3d p = T.translation();
		char b[400];
		std::snprintf(
			b, sizeof b, "%lld,INS_SOLUTION_GOOD,51.76,-1.26,110.0,%.9f,%.9f,%.9f,30U,0,0,0,%.12f,%.12f,%.12f\n",
			static_cast<long long>(t), p.x(), p.y(), p.z(), ypr[2], ypr[1], ypr[0]);
		f << b;
	}
}

/** One frame of a traversal: both mosaics, and its stereo.timestamps line. */
void writeFrame(const std::string& traversal, int64_t t, const cv::Mat& left, const cv::Mat& right)
{
	const std::string name = std::to_string(t) + ".png";
	EXPECT_TRUE(cv::imwrite(traversal + "/stereo/left/" + name, mosaicGBRG(left)));
	EXPECT_TRUE(cv::imwrite(traversal + "/stereo/right/" + name, mosaicGBRG(right)));
	std::ofstream(traversal + "/stereo.timestamps", std::ios::app) << t << " 1\n";
}

struct TReplica
{
	std::string traversal, models, extrinsics;
};

TReplica replicaFolders(const std::string& dir, const std::string& name)
{
	TReplica r{dir + "/" + name, dir + "/models", dir + "/extrinsics"};
	for (const char* sub : {"/stereo/left", "/stereo/right", "/gps", "/vo"}) fs::create_directories(r.traversal + sub);
	std::ofstream(r.traversal + "/vo/vo.csv") << "source_timestamp,destination_timestamp,x,y,z,roll,pitch,yaw\n";
	writeExtrinsics(r.extrinsics);
	return r;
}

/** A RobotCar traversal of the corridor's frames, with models whose LUT
 * shifts by (du, dv) pixels, and INS rows every 20 ms, 7 ms off the frames,
 * from 53 ms before frame 0 to 60 ms after the last. */
TReplica makeReplica(const std::string& dir, double du = 0, double dv = 0)
{
	const auto r = replicaFolders(dir, "2014-12-12-10-45-15");
	const auto& s = corridor();
	for (int k = 0; k < kRobotCarFrames; k++) writeFrame(r.traversal, kT0 + k * kFramePeriod, s.left[k], s.right[k]);
	writeModels(r.models, s.calib, s.left[0].cols, s.left[0].rows, du, dv);
	std::vector<std::pair<int64_t, Eigen::Isometry3d>> ins;
	for (int64_t t = kT0 - 53000; t <= kT0 + (kRobotCarFrames - 1) * kFramePeriod + 60000; t += 20000)
		ins.push_back({t, leftPoseAt(double(t - kT0) / kFramePeriod)});
	writeIns(r.traversal + "/gps/ins.csv", ins);
	return r;
}

/** Mean and maximum |a - b| over every channel of the window `roi` of both. */
std::pair<double, double> imageError(const cv::Mat& a, const cv::Mat& b)
{
	cv::Mat d;
	cv::absdiff(a, b, d);
	double mx = 0;
	cv::minMaxLoc(d.reshape(1), nullptr, &mx);
	const cv::Scalar m = cv::mean(d);
	return {(m[0] + m[1] + m[2]) / 3, mx};
}

RobotCarImporter importer(const TReplica& r)
{
	RobotCarImporter imp;
	imp.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	imp.modelsDir = r.models;
	imp.extrinsicsDir = r.extrinsics;
	return imp;
}

void expectNoRobotCarOutput(const std::string& out)
{
	const fs::path p(out);
	for (const std::string& q :
		 {out, (p.parent_path() / ("." + p.filename().string() + ".tmp")).string(), shadyloc::io::imagesDirFor(out),
		  groundTruthPathFor(out)})
		EXPECT_FALSE(fs::exists(q)) << "left behind: " << q;
	for (const auto& e : fs::directory_iterator(p.parent_path()))
		EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();
}
}  // namespace

TEST(DatasetsRobotCar, BayerGbrgCodeGivesTheMosaickedColour)
{
	// A flat colour survives mosaicking and demosaicing exactly only with the
	// right Bayer code; a wrong one swaps red and blue or greys the image.
	const cv::Mat bgr(16, 16, CV_8UC3, cv::Scalar(10, 100, 200));
	TRobotCarCameraModel m;
	m.name = "flat";
	m.mapX.create(16, 16, CV_32FC1);
	m.mapY.create(16, 16, CV_32FC1);
	for (int r = 0; r < 16; r++)
		for (int c = 0; c < 16; c++) m.mapX.at<float>(r, c) = float(c), m.mapY.at<float>(r, c) = float(r);
	const cv::Mat out = m.rectify(mosaicGBRG(bgr), "flat");
	EXPECT_EQ(imageError(out, bgr).second, 0.0);
}

TEST(DatasetsRobotCar, RoundTripImagesCalibrationAndGroundTruth)
{
	const std::string dir = shadyloc::test::tempDir("robotcar_ok");
	const auto rep = makeReplica(dir);
	auto imp = importer(rep);
	const std::string out = dir + "/rc.rawlog";
	const auto res = imp.run(rep.traversal, out);
	ASSERT_EQ(res.frames, size_t(kRobotCarFrames));
	const auto& s = corridor();

	const auto obs = shadyloc::test::readStereoFrames(out);
	ASSERT_EQ(obs.size(), size_t(kRobotCarFrames));
	for (int k = 0; k < kRobotCarFrames; k++)
	{
		const auto& o = *obs[k];
		EXPECT_NEAR(mrpt::Clock::toDouble(o.timestamp), (kT0 + k * kFramePeriod) * 1e-6, 3e-7);	 // 100 ns ticks of a 1.4e9 s double
		EXPECT_EQ(o.leftCamera.ncols, uint32_t(s.left[0].cols));
		EXPECT_NEAR(o.leftCamera.fx(), s.calib.fx, 1e-6);
		EXPECT_NEAR(o.leftCamera.fy(), s.calib.fy, 1e-6);
		EXPECT_NEAR(o.leftCamera.cx(), s.calib.cx, 1e-6);
		EXPECT_NEAR(o.leftCamera.cy(), s.calib.cy, 1e-6);
		EXPECT_NEAR(o.rightCamera.cx(), s.calib.cxR, 1e-6);
		EXPECT_NEAR(o.rightCameraPose.x(), s.calib.baseline, 1e-6);
		for (auto [got, want] : {std::pair{&o.imageLeft, &s.left[k]}, std::pair{&o.imageRight, &s.right[k]}})
		{
			// The only loss is demosaicing: the output is OpenCV's bilinear
			// demosaic of the mosaic, bit for bit (identity table)...
			cv::Mat ref;
			cv::cvtColor(mosaicGBRG(*want), ref, cv::COLOR_BayerGBRG2BGR);
			EXPECT_EQ(imageError(got->asCvMatRef(), ref).second, 0.0) << "frame " << k;
			// ... which is within kDemosaicError of the simulator's image
			// (two thirds of each pixel's values interpolated from the
			// corridor's fine, saturated texture), and a misregistration by
			// one pixel would be far further off.
			EXPECT_LT(imageError(got->asCvMatRef(), *want).first, kDemosaicError) << "frame " << k;
			EXPECT_GT(imageError(got->asCvMatRef()(kInner), (*want)(kInner + cv::Point(1, 0))).first, kMisregistered);
			EXPECT_GT(imageError(got->asCvMatRef()(kInner), (*want)(kInner + cv::Point(0, 1))).first, kMisregistered);
		}
	}

	// Ground truth: the left camera's pose at each image time, interpolated
	// from INS rows 7 ms away (the motion's curvature over 20 ms gives < 0.1 mm).
	const auto gt = shadyloc::io::readTum(res.groundTruthPath);
	ASSERT_EQ(gt.size(), size_t(kRobotCarFrames));
	for (int k = 0; k < kRobotCarFrames; k++)
	{
		EXPECT_NEAR(gt[k].t, mrpt::Clock::toDouble(obs[k]->timestamp), 1e-9);
		const Eigen::Isometry3d E = s.T_world_left[k].inverse() * gt[k].T;
		EXPECT_LT(E.translation().norm(), 1e-4) << "frame " << k;
		EXPECT_LT(Eigen::AngleAxisd(E.linear()).angle(), 1e-5) << "frame " << k;
	}

	// --gt-origin shifts the positions only.
	std::string text;
	ASSERT_EQ(
		shadyloc::test::runCommand(
			shadyloc::test::appPath() + " import robotcar -q " + rep.traversal + " -m " + rep.models + " -e " +
				rep.extrinsics + " --gt-origin 1.5,-2,0.25 -o " + dir + "/shifted.rawlog",
			&text),
		0)
		<< text;
	const auto shifted = shadyloc::io::readTum(groundTruthPathFor(dir + "/shifted.rawlog"));
	ASSERT_EQ(shifted.size(), gt.size());
	for (size_t k = 0; k < gt.size(); k++)
	{
		EXPECT_LT((shifted[k].T.translation() + Eigen::Vector3d(1.5, -2, 0.25) - gt[k].T.translation()).norm(), 3e-9);
		EXPECT_LT((shifted[k].T.linear() - gt[k].T.linear()).norm(), 1e-8);
	}
}

TEST(DatasetsRobotCar, HalfResolutionDemosaicingMeasuresEveryColour)
{
	// One pixel per Bayer cell: the output is the 2x2 mean of the simulator's
	// image but for blue and red, each sampled at one corner of the cell; the
	// intrinsics describe the half-resolution pixel grid.
	const std::string dir = shadyloc::test::tempDir("robotcar_half");
	const auto rep = makeReplica(dir);
	auto imp = importer(rep);
	imp.demosaic = TDemosaic::HalfResolution;
	const auto res = imp.run(rep.traversal, dir + "/rc.rawlog");
	const auto& s = corridor();
	EXPECT_EQ(res.leftCamera.ncols, uint32_t(s.left[0].cols / 2));
	EXPECT_EQ(res.leftCamera.nrows, uint32_t(s.left[0].rows / 2));
	EXPECT_NEAR(res.leftCamera.fx(), s.calib.fx / 2, 1e-6);
	EXPECT_NEAR(res.leftCamera.cx(), (s.calib.cx - 0.5) / 2, 1e-6);
	EXPECT_NEAR(res.leftCamera.cy(), (s.calib.cy - 0.5) / 2, 1e-6);
	EXPECT_NEAR(res.rightCamera.cx(), (s.calib.cxR - 0.5) / 2, 1e-6);
	EXPECT_NEAR(res.rightCameraPose.x(), s.calib.baseline, 1e-9);
	const auto obs = shadyloc::test::readStereoFrames(dir + "/rc.rawlog");
	ASSERT_EQ(obs.size(), size_t(kRobotCarFrames));
	for (int k = 0; k < kRobotCarFrames; k++)
	{
		// Green exactly (the identity table, halved, samples cell centres).
		cv::Mat want, got = obs[k]->imageLeft.asCvMatRef();
		std::vector<cv::Mat> gotCh, full;
		cv::split(got, gotCh);
		cv::split(s.left[k], full);
		for (int r = 0; r < got.rows; r++)
			for (int c = 0; c < got.cols; c++)
			{
				const int g = (full[1].at<uint8_t>(2 * r, 2 * c) + full[1].at<uint8_t>(2 * r + 1, 2 * c + 1) + 1) / 2;
				ASSERT_EQ(gotCh[1].at<uint8_t>(r, c), g) << "frame " << k << " at " << r << "," << c;
				ASSERT_EQ(gotCh[0].at<uint8_t>(r, c), full[0].at<uint8_t>(2 * r, 2 * c + 1));
				ASSERT_EQ(gotCh[2].at<uint8_t>(r, c), full[2].at<uint8_t>(2 * r + 1, 2 * c));
			}
	}
}

TEST(DatasetsRobotCar, CommandWithLutShiftCropAndFrameRange)
{
	// A LUT that samples (c + 3, r + 2) of the raw image, a crop, frames 1
	// and 3 (stride 2): through the command line.
	const std::string dir = shadyloc::test::tempDir("robotcar_cli");
	const auto rep = makeReplica(dir, 3, 2);
	const std::string out = dir + "/rc.rawlog";
	std::string text;
	const int rc = shadyloc::test::runCommand(
		shadyloc::test::appPath() + " import robotcar " + rep.traversal + " -m " + rep.models + " -e " + rep.extrinsics +
			" --first-frame 1 --stride 2 --max-frames 2 --crop 8,4,300,200 --progress-every 1 -o " + out,
		&text);
	ASSERT_EQ(rc, 0) << text;
	EXPECT_NE(text.find("2 frames imported"), std::string::npos) << text;  // progress
	const auto& s = corridor();
	const auto obs = shadyloc::test::readStereoFrames(out);
	ASSERT_EQ(obs.size(), 2u);
	for (int j = 0; j < 2; j++)
	{
		const int k = 1 + 2 * j;
		const auto& o = *obs[j];
		EXPECT_NEAR(mrpt::Clock::toDouble(o.timestamp), (kT0 + k * kFramePeriod) * 1e-6, 3e-7);
		EXPECT_EQ(o.leftCamera.ncols, 300u);
		EXPECT_EQ(o.leftCamera.nrows, 200u);
		EXPECT_NEAR(o.leftCamera.cx(), s.calib.cx - 8, 1e-6);
		EXPECT_NEAR(o.leftCamera.cy(), s.calib.cy - 4, 1e-6);
		EXPECT_NEAR(o.rightCamera.cx(), s.calib.cxR - 8, 1e-6);
		// Output (r, c) is raw (r + 4 + 2, c + 8 + 3).
		const cv::Rect src(8 + 3, 4 + 2, 300, 200);
		EXPECT_LT(imageError(o.imageLeft.asCvMatRef(), s.left[k](src)).first, kDemosaicError) << "frame " << k;
		EXPECT_LT(imageError(o.imageRight.asCvMatRef(), s.right[k](src)).first, kDemosaicError) << "frame " << k;
		EXPECT_GT(imageError(o.imageLeft.asCvMatRef(), s.left[k](src + cv::Point(1, 0))).first, kMisregistered);
		EXPECT_GT(imageError(o.imageLeft.asCvMatRef(), s.left[k](src + cv::Point(0, 1))).first, kMisregistered);
	}
	const auto gt = shadyloc::io::readTum(groundTruthPathFor(out));
	ASSERT_EQ(gt.size(), 2u);
	EXPECT_LT((gt[1].T.translation() - s.T_world_left[3].translation()).norm(), 1e-4);

	// Usage errors: exit 2, nothing written.
	const std::string bad = dir + "/bad.rawlog";
	for (const std::string& args :
		 {" -m " + rep.models + " -o " + bad,	// neither --extrinsics nor --no-ground-truth
		  " -m " + rep.models + " --no-ground-truth --crop 1,2,3 -o " + bad,
		  " -m " + rep.models + " --no-ground-truth --stride 0 -o " + bad,
		  " -m " + rep.models + " -e " + rep.extrinsics + " --gt-origin 1,2 -o " + bad,
		  " -m " + rep.models + " --no-ground-truth --gt-origin 1,2,3 -o " + bad})
	{
		EXPECT_EQ(shadyloc::test::runCommand(shadyloc::test::appPath() + " import robotcar " + rep.traversal + args, &text), 2)
			<< args << "\n" << text;
		EXPECT_FALSE(fs::exists(bad));
	}
}

TEST(DatasetsRobotCar, BadInputNamesTheCulpritAndLeavesNothing)
{
	const std::string dir = shadyloc::test::tempDir("robotcar_bad");
	const std::string out = dir + "/out/rc.rawlog";
	fs::create_directories(dir + "/out");
	auto expectError = [&](const TReplica& rep, const std::string& needle) {
		auto imp = importer(rep);
		try
		{
			imp.run(rep.traversal, out);
			ADD_FAILURE() << "import succeeded, expected an error naming '" << needle << "'";
		}
		catch (const DatasetError& e)
		{
			EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
		}
		expectNoRobotCarOutput(out);
	};
	const auto rep = makeReplica(dir);
	const std::string stamps = rep.traversal + "/stereo.timestamps";
	const std::string ins = rep.traversal + "/gps/ins.csv";

	// Missing models: the intrinsics, then the look-up table.
	fs::rename(rep.models + "/stereo_wide_right.txt", dir + "/r.txt");
	expectError(rep, "stereo_wide_right.txt': no such camera model");
	fs::rename(dir + "/r.txt", rep.models + "/stereo_wide_right.txt");
	fs::rename(rep.models + "/stereo_wide_left_distortion_lut.bin", dir + "/l.bin");
	expectError(rep, "stereo_wide_left_distortion_lut.bin': no such look-up table");
	// A LUT for another image size.
	fs::resize_file(dir + "/l.bin", 1000 * sizeof(double));
	fs::copy_file(dir + "/l.bin", rep.models + "/stereo_wide_left_distortion_lut.bin");
	expectError(rep, "8000 bytes, expected");
	writeLut(rep.models, "stereo_wide_left", corridor().left[0].cols, corridor().left[0].rows, 0, 0);

	// A timestamp with no image (the right one of frame 3).
	const std::string t3 = std::to_string(kT0 + 3 * kFramePeriod);
	fs::rename(rep.traversal + "/stereo/right/" + t3 + ".png", dir + "/t3.png");
	expectError(rep, "stereo.timestamps':4: timestamp " + t3 + " has no right image");
	fs::rename(dir + "/t3.png", rep.traversal + "/stereo/right/" + t3 + ".png");

	// A truncated ins.csv: the last row cut mid-number, or inside its last
	// number (which still parses: the missing newline tells).
	const auto insBytes = fs::file_size(ins);
	fs::copy_file(ins, dir + "/ins.csv");
	for (int cut : {30, 3})
	{
		fs::copy_file(dir + "/ins.csv", ins, fs::copy_options::overwrite_existing);
		fs::resize_file(ins, insBytes - cut);
		expectError(rep, "gps/ins.csv':32: the last line does not end with a newline (truncated file?)");
	}
	// A row with fields missing (the columns would shift).
	{
		std::ifstream f(dir + "/ins.csv");
		std::string all((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
		const size_t row5 = [&] { size_t p = 0; for (int i = 0; i < 4; i++) p = all.find('\n', p) + 1; return p; }();
		all.erase(all.find(',', row5), all.find(',', all.find(',', row5) + 1) - all.find(',', row5));  // drop ins_status
		std::ofstream(ins) << all;
	}
	expectError(rep, "gps/ins.csv':5: 14 fields, the header has 15 (truncated file?)");
	fs::copy_file(dir + "/ins.csv", ins, fs::copy_options::overwrite_existing);
	// ... cut after a whole row: it no longer covers the last frame.
	{
		std::ifstream f(dir + "/ins.csv");
		std::string all((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
		all.resize(all.rfind('\n', all.size() - 2) + 1);
		all.resize(all.rfind('\n', all.size() - 2) + 1);
		all.resize(all.rfind('\n', all.size() - 2) + 1);
		all.resize(all.rfind('\n', all.size() - 2) + 1);
		std::ofstream(ins) << all;
	}
	expectError(rep, "stereo.timestamps':6 (frame 5): no INS pose on both sides");
	fs::copy_file(dir + "/ins.csv", ins, fs::copy_options::overwrite_existing);

	// No extrinsics folder with ground truth on.
	fs::rename(rep.extrinsics, dir + "/extr");
	expectError(rep, "no such extrinsics folder");
	fs::rename(dir + "/extr", rep.extrinsics);

	// A demosaiced (colour) image where the raw mosaic belongs.
	const std::string t2 = std::to_string(kT0 + 2 * kFramePeriod);
	const std::string left2 = rep.traversal + "/stereo/left/" + t2 + ".png";
	fs::copy_file(left2, dir + "/l2.png");
	cv::imwrite(left2, corridor().left[2]);
	expectError(rep, "frame 2 (" + t2 + ") left: 3 channels, a raw Bayer mosaic has 1");
	fs::copy_file(dir + "/l2.png", left2, fs::copy_options::overwrite_existing);

	// Timestamps out of order.
	fs::copy_file(stamps, dir + "/stamps");
	std::ofstream(stamps, std::ios::app) << kT0 << " 1\n";
	expectError(rep, "stereo.timestamps':7: timestamp");
	std::ofstream(stamps) << "-" << kT0 << " 1\n";
	expectError(rep, "stereo.timestamps':1: timestamp -" + std::to_string(kT0) + " is not a Unix time in microseconds");
	fs::copy_file(dir + "/stamps", stamps, fs::copy_options::overwrite_existing);

	// Good again; then the command line's message and exit status for one case.
	auto imp = importer(rep);
	EXPECT_EQ(imp.run(rep.traversal, out).frames, size_t(kRobotCarFrames));
	fs::remove(out);
	fs::remove(groundTruthPathFor(out));
	fs::rename(rep.models + "/stereo_wide_left.txt", dir + "/l.txt");
	std::string text;
	EXPECT_EQ(
		shadyloc::test::runCommand(
			shadyloc::test::appPath() + " import robotcar " + rep.traversal + " -m " + rep.models + " -e " +
				rep.extrinsics + " -o " + out,
			&text),
		1)
		<< text;
	EXPECT_NE(text.find("stereo_wide_left.txt': no such camera model"), std::string::npos) << text;
	expectNoRobotCarOutput(out);
}

namespace
{
/** A number of summary.json's "ground_truth" object. */
double groundTruthFigure(const std::string& summaryPath, const std::string& key)
{
	const std::string text = shadyloc::test::fileContents(summaryPath);
	const size_t gt = text.find("\"ground_truth\"");
	const size_t at = text.find("\"" + key + "\": ", gt);
	if (gt == std::string::npos || at == std::string::npos) return -1;
	return std::strtod(text.c_str() + at + key.size() + 4, nullptr);
}

/** A simulator traversal (rawlog + TUM) written as a RobotCar traversal:
 * raw GBRG mosaics at microsecond times, identity look-up tables, INS rows
 * at the ground truth's times. */
void simToReplica(const std::string& rawlog, const std::string& tum, const TReplica& r)
{
	namespace io = shadyloc::io;
	io::TStereoFrameSourceOptions so;
	so.sensorLabel = io::findStereoLabel(rawlog, io::labelWithoutSuffixes({"_mono", "_inv", "_lin"}));
	io::StereoFrameSource source(rawlog, so);
	io::TStereoFrame f;
	while (source.next(f))
	{
		if (f.index == 0) writeModels(r.models, f.calib, f.left.cols, f.left.rows, 0, 0);
		writeFrame(r.traversal, std::llround(f.timestamp * 1e6), f.left, f.right);
	}
	std::vector<std::pair<int64_t, Eigen::Isometry3d>> ins;
	for (const auto& p : io::readTum(tum)) ins.push_back({std::llround(p.t * 1e6), p.T});
	writeIns(r.traversal + "/gps/ins.csv", ins);
}
}  // namespace

/** "accepted" of one localiser's entry of summary.json. */
int acceptedBy(const std::string& summaryPath, const std::string& channel)
{
	const std::string text = shadyloc::test::fileContents(summaryPath);
	const size_t at = text.find("{\"channel\": \"" + channel + "\", \"accepted\": ");
	return at == std::string::npos ? -1 : std::atoi(text.c_str() + at + channel.size() + 28);
}

// The must-show 1: replica RobotCar traversals (the default data's
// noon and overcast, as raw mosaics) import, the noon replica surveys, and
// the overcast replica localises against it; compared with the simulator's
// own rawlogs of those frames. Measured (2-core VM, seventeenth session):
// 99.19 % true coverage in map with the simulator's rawlogs, with the
// replicas' bilinear and edge-aware demosaicing alike, 95.16 % at half
// resolution; no false fix. The mosaic still costs the invariant channel
// most of its own fixes (122 accepted on the simulator's rawlogs, 18 / 18 /
// 7 on the replicas); mono carries the frames (121 / 121 / 120 / 105). The
// two full-resolution replicas must stay within the 1 point; half
// resolution is guarded at its measured loss plus 2 points
// (docs/datasets.md). Needs the default dataset (rawlogs/generated or the
// ctest fixture default_data; skipped without either); about three minutes
// on two cores.
TEST(LocalisationRobotCarReplica, CoverageAgainstTheSimulatorsRawlogs)
{
	SHADYLOC_REQUIRE_DEFAULT_DATASET();
	const std::string src = SHADYLOC_SOURCE_DIR, data = shadyloc::test::defaultDatasetDir();
	const std::string dir = shadyloc::test::tempDir("robotcar_replica_localise");
	const std::string app = "'" + shadyloc::test::appPath() + "' ";
	const std::string cfg = " -c '" + src + "/config/vo_sim.ini' ";
	auto run = [](const std::string& cmd) {
		std::string out;
		EXPECT_EQ(shadyloc::test::runCommand(cmd, &out), 0) << cmd << "\n" << out;
	};
	// rawlog and ground truth of each traversal, per source.
	const std::vector<std::string> sources = {"sim", "bilinear", "edge-aware", "half"};
	std::map<std::string, std::map<std::string, std::pair<std::string, std::string>>> runs;
	for (const std::string t : {"noon", "overcast"})
	{
		const auto r = replicaFolders(dir, t);
		simToReplica(data + "/" + t + ".rawlog", data + "/" + t + ".tum", r);
		runs["sim"][t] = {data + "/" + t + ".rawlog", data + "/" + t + ".tum"};
		for (const std::string m : {"bilinear", "edge-aware", "half"})
		{
			const std::string out = dir + "/" + m + "_" + t + ".rawlog";
			run(app + "import robotcar -q " + r.traversal + " -m " + r.models + " -e " + r.extrinsics + " --demosaic " + m + " -o " + out);
			runs[m][t] = {out, groundTruthPathFor(out)};
		}
	}
	std::map<std::string, double> coverage;
	for (const auto& s : sources)
	{
		auto& set = runs[s];
		const std::string map = dir + "/" + s + "_noon.kfmap", out = dir + "/" + s + "_loc";
		run(app + "survey -q -i " + set["noon"].first + " -o " + map + cfg + "--gt " + set["noon"].second);
		run(app + "localise -q -m " + map + " -i " + set["overcast"].first + " -o " + out + cfg + "-c '" + src +
			"/config/localise_sim.ini' --gt " + set["overcast"].second);
		const std::string summary = out + "/summary.json";
		coverage[s] = groundTruthFigure(summary, "true_coverage_in_map");
		std::printf(
			"%-10s: overcast against the noon map, true coverage in map %.4f, false fixes %.0f; accepted: mono %d, invariant %d\n",
			s.c_str(), coverage[s], groundTruthFigure(summary, "false_fixes"), acceptedBy(summary, "mono"),
			acceptedBy(summary, "invariant"));
		EXPECT_EQ(groundTruthFigure(summary, "false_fixes"), 0.0) << s;
	}
	ASSERT_GT(coverage["sim"], 0.9);
	EXPECT_GE(coverage["bilinear"], coverage["sim"] - 0.01);
	EXPECT_GE(coverage["edge-aware"], coverage["sim"] - 0.01);
	EXPECT_GE(coverage["half"], coverage["sim"] - 0.06);
}
