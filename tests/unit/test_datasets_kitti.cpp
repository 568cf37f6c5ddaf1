/* ShadyLoc tests: KITTI layout -> rawlog -> KITTI layout, and bad input. */
#include <shadyloc/datasets/Kitti.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/Tum.h>

#include "../support/TestSupport.h"

#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>

using namespace shadyloc::datasets;
namespace fs = std::filesystem;

namespace
{
constexpr int kW = 64, kH = 40, kKittiFrames = 5;

// KITTI odometry sequence 00's colour projection matrices (fx, cx, cy and the
// non-zero P[1][3], P[2][3] terms included), for an image of kW x kH.
const double kP[4][12] = {
	{718.856, 0, 607.1928, 0, 0, 718.856, 185.2157, 0, 0, 0, 1, 0},
	{718.856, 0, 607.1928, -386.1448, 0, 718.856, 185.2157, 0, 0, 0, 1, 0},
	{718.856, 0, 607.1928, 45.38225, 0, 718.856, 185.2157, -0.1130887, 0, 0, 1, 0.003779761},
	{718.856, 0, 607.1928, -337.2877, 0, 718.856, 185.2157, 2.369057, 0, 0, 1, 0.004915215}};

/** Poses as 3x4 row-major; `fmt` is the printf format of one number. */
std::vector<std::array<double, 12>> g_poses;

/** A KITTI tree: random colour PNGs, calib.txt (P0..P3, Tr), times.txt,
 * poses/00.txt printed with `poseFmt`. */
void makeKittiTree(const std::string& root, const char* poseFmt = "%.12e", int frames = kKittiFrames)
{
	const fs::path seq = fs::path(root) / "sequences" / "00";
	fs::create_directories(seq / "image_2");
	fs::create_directories(seq / "image_3");
	fs::create_directories(fs::path(root) / "poses");
	cv::RNG rng(42);
	char name[32];
	for (int i = 0; i < frames; i++)
	{
		std::snprintf(name, sizeof(name), "%06d.png", i);
		for (const char* sub : {"image_2", "image_3"})
		{
			cv::Mat m(kH, kW, CV_8UC3);
			rng.fill(m, cv::RNG::UNIFORM, 0, 256);
			ASSERT_TRUE(cv::imwrite((seq / sub / name).string(), m));
		}
	}
	{
		std::ofstream f(seq / "calib.txt");
		for (int k = 0; k < 4; k++)
		{
			f << "P" << k << ":";
			for (double v : kP[k]) f << " " << std::scientific << std::setprecision(12) << v;
			f << "\n";
		}
		f << "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n";
	}
	{
		std::ofstream f(seq / "times.txt");
		for (int i = 0; i < frames; i++)
		{
			std::snprintf(name, sizeof(name), "%e\n", 0.1036223 * i);
			f << name;
		}
	}
	std::mt19937 r(3);
	std::uniform_real_distribution<double> t(-40, 40), a(-M_PI, M_PI), p(-1.2, 1.2);
	g_poses.clear();
	std::ofstream f(fs::path(root) / "poses" / "00.txt");
	for (int i = 0; i < frames; i++)
	{
		const mrpt::poses::CPose3D P(t(r), t(r), t(r), a(r), p(r), a(r));
		std::array<double, 12> v;
		for (int row = 0; row < 3; row++)
		{
			for (int c = 0; c < 3; c++) v[row * 4 + c] = P.getRotationMatrix()(row, c);
			v[row * 4 + 3] = P[row];
		}
		for (int k = 0; k < 12; k++)
		{
			char buf[40];
			std::snprintf(buf, sizeof(buf), poseFmt, v[k]);
			f << (k ? " " : "") << buf;
			v[k] = std::strtod(buf, nullptr);  // what a reader of the file sees
		}
		f << "\n";
		g_poses.push_back(v);
	}
}

std::vector<std::array<double, 12>> readPoses(const std::string& path)
{
	std::vector<std::array<double, 12>> out;
	std::ifstream f(path);
	std::array<double, 12> v;
	while (f >> v[0])
	{
		for (int k = 1; k < 12; k++) f >> v[k];
		out.push_back(v);
	}
	return out;
}

std::vector<std::string> readLines(const std::string& path)
{
	std::vector<std::string> out;
	std::ifstream f(path);
	std::string l;
	while (std::getline(f, l)) out.push_back(l);
	return out;
}

/** Nothing of a failed import may remain: rawlog, temporaries, images, ground truth. */
void expectNoOutput(const std::string& out)
{
	const fs::path p(out);
	for (const std::string& q :
		 {out, out + ".tmp", (p.parent_path() / ("." + p.filename().string() + ".tmp")).string(),
		  shadyloc::io::imagesDirFor(out), shadyloc::io::imagesDirFor(out) + ".tmp",
		  groundTruthPathFor(out)})
		EXPECT_FALSE(fs::exists(q)) << "left behind: " << q;
}

/** Runs the importer expecting a DatasetError whose message holds `needle`. */
void expectImportError(
	const std::string& root, const std::string& out, const std::string& needle, bool external = false)
{
	KittiImporter imp;
	imp.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	imp.options.externalImages = external;
	try
	{
		imp.run(root, "00", out);
		ADD_FAILURE() << "import succeeded, expected an error naming '" << needle << "'";
	}
	catch (const DatasetError& e)
	{
		EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
			<< "message does not name '" << needle << "': " << e.what();
	}
	expectNoOutput(out);
}
}  // namespace

TEST(DatasetsKitti, CalibrationGeometryFromProjectionMatrices)
{
	TMatrix34 P2, P3;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 4; c++) P2(r, c) = kP[2][r * 4 + c], P3(r, c) = kP[3][r * 4 + c];
	const auto t2 = translationFromProjection(P2), t3 = translationFromProjection(P3);
	// Back-substitution of P[:,3] = K t, by hand for sequence 00:
	// t2.x = (45.38225 - 607.1928 * 0.003779761) / 718.856.
	EXPECT_NEAR(t2.x, (45.38225 - 607.1928 * 0.003779761) / 718.856, 1e-15);
	EXPECT_NEAR(t2.z, 0.003779761, 1e-15);
	// The colour baseline of KITTI is about 0.53 m.
	EXPECT_NEAR(t2.x - t3.x, 0.5333, 1e-3);
	// projectionFromCamera inverts the two (rounding only: 1e-12 relative).
	const auto cam = cameraFromProjection(P2, 1241, 376);
	const auto P2b = projectionFromCamera(cam, t2);
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 4; c++) EXPECT_NEAR(P2b(r, c), P2(r, c), 1e-12 * (1 + std::abs(P2(r, c))));
}

class DatasetsKittiRoundTrip : public ::testing::TestWithParam<bool>
{
};

TEST_P(DatasetsKittiRoundTrip, ImagesBitExactPosesToPrintPrecision)
{
	const bool external = GetParam();
	const std::string dir = shadyloc::test::tempDir(external ? "kitti_rt_ext" : "kitti_rt");
	const std::string rootA = dir + "/A", rootB = dir + "/B", rawlog = dir + "/seq.rawlog";
	makeKittiTree(rootA);

	KittiImporter imp;
	imp.setMinLoggingLevel(mrpt::system::LVL_WARN);
	imp.options.externalImages = external;
	const auto res = imp.run(rootA, "00", rawlog);
	ASSERT_EQ(res.frames, size_t(kKittiFrames));
	ASSERT_EQ(res.groundTruthPath, groundTruthPathFor(rawlog));
	ASSERT_TRUE(fs::exists(res.groundTruthPath));
	EXPECT_EQ(fs::is_directory(shadyloc::io::imagesDirFor(rawlog)), external);

	// What the rawlog holds: calibration, baseline, timestamps, BGR images.
	const auto obs = shadyloc::test::readStereoFrames(rawlog);
	ASSERT_EQ(obs.size(), size_t(kKittiFrames));
	const double t2x = (kP[2][3] - kP[2][2] * kP[2][11]) / kP[2][0];
	const double t3x = (kP[3][3] - kP[3][2] * kP[3][11]) / kP[3][0];
	for (int i = 0; i < kKittiFrames; i++)
	{
		const auto& o = *obs[i];
		EXPECT_EQ(o.sensorLabel, "CAMERA");
		EXPECT_EQ(o.leftCamera.ncols, uint32_t(kW));
		EXPECT_EQ(o.leftCamera.nrows, uint32_t(kH));
		EXPECT_EQ(o.leftCamera.fx(), 718.856);
		EXPECT_EQ(o.leftCamera.cx(), 607.1928);
		EXPECT_EQ(o.rightCamera.cy(), 185.2157);
		EXPECT_NEAR(o.rightCameraPose.x(), t2x - t3x, 1e-12);	 // only rounding
		EXPECT_EQ(o.rightCameraPose.y(), 0.0);
		// Timestamps: nearest 100 ns Clock tick of times.txt ("%e": 7 digits).
		EXPECT_NEAR(mrpt::Clock::toDouble(o.timestamp), std::stod(readLines(rootA + "/sequences/00/times.txt")[i]), 5e-8);
		char name[32];
		std::snprintf(name, sizeof(name), "/%06d.png", i);
		EXPECT_TRUE(shadyloc::test::samePixels(o.imageLeft.asCvMatRef(), cv::imread(rootA + "/sequences/00/image_2" + name)));
		EXPECT_TRUE(shadyloc::test::samePixels(o.imageRight.asCvMatRef(), cv::imread(rootA + "/sequences/00/image_3" + name)));
	}

	KittiExporter exp;
	exp.setMinLoggingLevel(mrpt::system::LVL_WARN);
	exp.options.groundTruthTum = res.groundTruthPath;
	const auto er = exp.run(rawlog, rootB);
	EXPECT_EQ(er.frames, size_t(kKittiFrames));
	EXPECT_TRUE(er.poses);

	// Images: decoded pixels identical, same names.
	for (const char* sub : {"image_2", "image_3"})
	{
		const auto a = readLines(rootA + "/sequences/00/times.txt");
		for (int i = 0; i < kKittiFrames; i++)
		{
			char name[32];
			std::snprintf(name, sizeof(name), "/%s/%06d.png", sub, i);
			const cv::Mat ia = cv::imread(rootA + "/sequences/00" + name, cv::IMREAD_UNCHANGED);
			const cv::Mat ib = cv::imread(rootB + "/sequences/00" + name, cv::IMREAD_UNCHANGED);
			ASSERT_FALSE(ib.empty()) << name;
			EXPECT_TRUE(shadyloc::test::samePixels(ia, ib)) << name << " differs after the round trip";
		}
	}
	EXPECT_FALSE(fs::exists(rootB + "/sequences/00/image_2/" + std::to_string(kKittiFrames) + ".png"));

	// Times: A starts at 0, so relative times equal A's, to the 100 ns tick.
	const auto ta = readLines(rootA + "/sequences/00/times.txt"), tb = readLines(rootB + "/sequences/00/times.txt");
	ASSERT_EQ(ta.size(), tb.size());
	for (size_t i = 0; i < ta.size(); i++) EXPECT_NEAR(std::stod(ta[i]), std::stod(tb[i]), 5e-8);

	// Calibration: B's reference camera is the left colour camera, so its P2
	// has t = 0 and P3 carries the baseline.
	const auto cb = TKittiCalib::FromFile(rootB + "/sequences/00/calib.txt");
	const auto tb2 = translationFromProjection(cb.get("P2", "B")), tb3 = translationFromProjection(cb.get("P3", "B"));
	EXPECT_EQ(tb2.x, 0.0);
	EXPECT_NEAR(tb2.x - tb3.x, t2x - t3x, 1e-11);	// "%.12e" printing: 13 digits
	EXPECT_EQ(cb.get("P2", "B")(0, 2), 607.1928);

	// Poses: B holds T_world_left = T_world_cam0 * T_cam0_cam2 (docs/datasets.md).
	// A's poses are printed with 13 digits (exact rotations to 1e-12); the
	// TUM step rounds translation to 5e-10 m and quaternion components to
	// 5e-10 (=> rotation entries to ~4e-9); B prints with "%.9e" (relative
	// 5e-10). Bounds: rotation entries 1e-8, translation 1e-9 (1 + |t|).
	const auto pb = readPoses(rootB + "/poses/00.txt");
	ASSERT_EQ(pb.size(), g_poses.size());
	TMatrix34 P2A;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 4; c++) P2A(r, c) = kP[2][r * 4 + c];
	const auto t2 = translationFromProjection(P2A);
	for (size_t i = 0; i < pb.size(); i++)
	{
		const auto& a = g_poses[i];
		for (int r = 0; r < 3; r++)
		{
			// Expected translation: t_a + R_a * (-t2).
			const double tExp = a[r * 4 + 3] - (a[r * 4] * t2.x + a[r * 4 + 1] * t2.y + a[r * 4 + 2] * t2.z);
			EXPECT_NEAR(pb[i][r * 4 + 3], tExp, 1e-9 * (1 + std::abs(tExp))) << "pose " << i << " row " << r;
			for (int c = 0; c < 3; c++)
				EXPECT_NEAR(pb[i][r * 4 + c], a[r * 4 + c], 1e-8) << "pose " << i << " R(" << r << "," << c << ")";
		}
	}

	// And B imports back to the same ground truth (a fixed point): B's cam0 is
	// the left camera, so no offset is added the second time.
	const std::string rawlog2 = dir + "/seq2.rawlog";
	const auto res2 = imp.run(rootB, "00", rawlog2);
	const auto g1 = shadyloc::io::readTum(res.groundTruthPath), g2 = shadyloc::io::readTum(res2.groundTruthPath);
	ASSERT_EQ(g1.size(), g2.size());
	for (size_t i = 0; i < g1.size(); i++)
	{
		EXPECT_NEAR(g1[i].t, g2[i].t, 5e-8);	// 100 ns clock ticks
		for (int k = 0; k < 3; k++)
		{
			const double a = g1[i].T.translation()[k], b = g2[i].T.translation()[k];
			EXPECT_NEAR(a, b, 2e-9 * (1 + std::abs(a)));
		}
	}
}
INSTANTIATE_TEST_SUITE_P(InlineAndExternalImages, DatasetsKittiRoundTrip, ::testing::Bool());

TEST(DatasetsKitti, KittiPrintPrecisionPosesSurvive)
{
	// KITTI's own files print 7 significant digits ("%e"), so their rotations
	// are orthonormal only to ~1e-6; the import projects them onto SO(3), which
	// moves entries by about that much: tolerance 3e-6.
	const std::string dir = shadyloc::test::tempDir("kitti_e");
	makeKittiTree(dir + "/A", "%e", 3);
	KittiImporter imp;
	imp.setMinLoggingLevel(mrpt::system::LVL_WARN);
	const auto res = imp.run(dir + "/A", "00", dir + "/s.rawlog");
	const auto gt = shadyloc::io::readTum(res.groundTruthPath);
	ASSERT_EQ(gt.size(), 3u);
	for (size_t i = 0; i < gt.size(); i++)
		for (int r = 0; r < 3; r++)
			for (int c = 0; c < 3; c++)
				EXPECT_NEAR(gt[i].T.linear()(r, c), g_poses[i][r * 4 + c], 3e-6);
}

TEST(DatasetsKitti, BadInputNamesTheCulpritAndLeavesNothing)
{
	const std::string dir = shadyloc::test::tempDir("kitti_bad");
	const std::string out = dir + "/out.rawlog";
	const std::string seq = dir + "/K/sequences/00";

	// Missing folder, missing sequence.
	expectImportError(dir + "/nope", out, dir + "/nope");
	makeKittiTree(dir + "/K");
	{
		KittiImporter imp;
		EXPECT_THROW(imp.run(dir + "/K", "07", out), DatasetError);
		expectNoOutput(out);
	}

	// calib.txt without P3.
	fs::copy_file(seq + "/calib.txt", dir + "/calib.bak");
	{
		auto lines = readLines(seq + "/calib.txt");
		std::ofstream f(seq + "/calib.txt");
		for (auto& l : lines)
			if (l.rfind("P3:", 0) != 0) f << l << "\n";
	}
	expectImportError(dir + "/K", out, "'P3:'");
	expectImportError(dir + "/K", out, seq + "/calib.txt");
	fs::copy_file(dir + "/calib.bak", seq + "/calib.txt", fs::copy_options::overwrite_existing);

	// Mismatched image counts.
	fs::rename(seq + "/image_3/000004.png", dir + "/r4.png");
	expectImportError(dir + "/K", out, "image_3' has 4");
	fs::rename(dir + "/r4.png", seq + "/image_3/000004.png");

	// times.txt with one line too few.
	fs::copy_file(seq + "/times.txt", dir + "/times.bak");
	{
		auto lines = readLines(seq + "/times.txt");
		std::ofstream f(seq + "/times.txt");
		for (size_t i = 0; i + 1 < lines.size(); i++) f << lines[i] << "\n";
	}
	expectImportError(dir + "/K", out, "times.txt' has 4 timestamps");
	fs::copy_file(dir + "/times.bak", seq + "/times.txt", fs::copy_options::overwrite_existing);

	// A repeated and a decreasing time (frame 3's): refused, naming the frame
	// and both times, as the folder importer does.
	for (const std::string& t3 : {std::string("2.072446e-01"), std::string("0.1")})
	{
		auto lines = readLines(dir + "/times.bak");
		ASSERT_EQ(lines[2], "2.072446e-01");
		lines[3] = t3;
		{
			std::ofstream f(seq + "/times.txt");
			for (const auto& l : lines) f << l << "\n";
		}
		expectImportError(dir + "/K", out, "times.txt': timestamp #3 (");
		expectImportError(dir + "/K", out, "is not after #2 (0.207244600 s)");
		std::string text;
		EXPECT_NE(shadyloc::test::runCommand(
					  shadyloc::test::appPath() + " import kitti '" + dir + "/K' --sequence 00 -q -o '" + out + "'", &text),
			0)
			<< text;
		EXPECT_NE(text.find("timestamp #3"), std::string::npos) << text;
		expectNoOutput(out);
	}
	fs::copy_file(dir + "/times.bak", seq + "/times.txt", fs::copy_options::overwrite_existing);

	// Mismatched sizes at frame 3: frames 0-2 are already written when it is
	// found, so this checks the atomic clean-up too (inline and external).
	fs::copy_file(seq + "/image_3/000003.png", dir + "/r3.png");
	cv::imwrite(seq + "/image_3/000003.png", cv::Mat(kH, kW + 6, CV_8UC3, cv::Scalar(1, 2, 3)));
	expectImportError(dir + "/K", out, "frame 3 ('000003.png')");
	expectImportError(dir + "/K", out, "70x40", true);
	fs::copy_file(dir + "/r3.png", seq + "/image_3/000003.png", fs::copy_options::overwrite_existing);

	// Unreadable image at frame 2.
	{
		std::ofstream f(seq + "/image_2/000002.png", std::ios::trunc);
		f << "not a png";
	}
	expectImportError(dir + "/K", out, seq + "/image_2/000002.png");
	expectImportError(dir + "/K", out, "frame 2", true);

	// The same through the app: non-zero exit, the file named, nothing left.
	std::string text;
	const int rc = shadyloc::test::runCommand(
		shadyloc::test::appPath() + " import kitti '" + dir + "/K' --sequence 00 -q -o '" + out + "'", &text);
	EXPECT_NE(rc, 0) << text;
	EXPECT_NE(text.find("image_2/000002.png"), std::string::npos) << text;
	expectNoOutput(out);
}

TEST(DatasetsKitti, ExportErrorsLeaveNoSequence)
{
	const std::string dir = shadyloc::test::tempDir("kitti_export_bad");
	const std::string rawlog = dir + "/syn.rawlog";
	shadyloc::test::writeSyntheticRawlog(rawlog, 3, true);	// sensory-frame style, label CAMERA

	// Wrong sensor label: error lists the labels present; no tree left.
	KittiExporter exp;
	exp.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	exp.options.sensorLabel = "STEREO";
	try
	{
		exp.run(rawlog, dir + "/out");
		ADD_FAILURE() << "export of a missing label succeeded";
	}
	catch (const DatasetError& e)
	{
		EXPECT_NE(std::string(e.what()).find("'CAMERA'"), std::string::npos) << e.what();
	}
	EXPECT_FALSE(fs::exists(dir + "/out")) << "export left directories behind";
	// The same through the app.
	std::string text;
	const int rc = shadyloc::test::runCommand(
		shadyloc::test::appPath() + " export kitti -q -i '" + rawlog + "' -o '" + dir +
			"/out' --sensor-label STEREO",
		&text);
	EXPECT_NE(rc, 0) << text;
	EXPECT_NE(text.find("no stereo observations labelled 'STEREO'"), std::string::npos) << text;
	EXPECT_FALSE(fs::exists(dir + "/out"));

	// Ground truth that does not cover frame 2 (t = 1000.2 s).
	// Identity poses spelt out: `{}` would value-construct an Isometry3d, which Eigen leaves uninitialised.
	shadyloc::io::Trajectory gt = {{1000.0, Eigen::Isometry3d::Identity()}, {1000.1, Eigen::Isometry3d::Identity()}};
	writeTum(dir + "/gt.tum", gt);
	exp.options.sensorLabel = "CAMERA";
	exp.options.groundTruthTum = dir + "/gt.tum";
	try
	{
		exp.run(rawlog, dir + "/out");
		ADD_FAILURE() << "export with incomplete ground truth succeeded";
	}
	catch (const DatasetError& e)
	{
		EXPECT_NE(std::string(e.what()).find("frame 2"), std::string::npos) << e.what();
	}
	EXPECT_FALSE(fs::exists(dir + "/out"));

	// Complete ground truth: 3 frames, poses written; the synthetic images
	// (BGR in the rawlog) come out as the same decoded pixels.
	gt.push_back({1000.2, shadyloc::io::toIsometry(mrpt::poses::CPose3D(1, 0, 0, 0, 0, 0))});
	writeTum(dir + "/gt.tum", gt);
	const auto r = exp.run(rawlog, dir + "/out");
	EXPECT_EQ(r.frames, 3u);
	ASSERT_EQ(readPoses(dir + "/out/poses/00.txt").size(), 3u);
	EXPECT_NEAR(readPoses(dir + "/out/poses/00.txt")[2][3], 1.0, 1e-12);
	const auto obs = shadyloc::test::syntheticStereoFrame(1);
	EXPECT_TRUE(shadyloc::test::samePixels(obs->imageLeft.asCvMatRef(), cv::imread(dir + "/out/sequences/00/image_2/000001.png")));
}
