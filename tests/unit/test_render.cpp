/* Offscreen trajectory snapshots (CFBORender through EGL/Mesa, headless). */
#include "../support/TestSupport.h"

#include <shadyloc/render/SceneSnapshot.h>
#include <shadyloc/render/TrajectorySnapshot.h>

#include "test_map_support.h"

#include <mrpt/opengl/CSetOfTriangles.h>

#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <iomanip>

using namespace shadyloc::render;

namespace
{
bool isRed(const cv::Vec3b& bgr) { return bgr[2] > 180 && bgr[1] < 90 && bgr[0] < 90; }
bool isBlue(const cv::Vec3b& bgr) { return bgr[0] > 180 && bgr[1] < 90 && bgr[2] < 90; }
}  // namespace

// Two straight paths at known places land where the projection says: the red
// one along the page centre line, the blue one below it (the camera's right),
// spanning the width minus the margins.
TEST(RenderSnapshot, PathsLandWhereTheProjectionPutsThem)
{
	const auto dir = shadyloc::test::tempDir("render");
	TrajectoryLayer red, blue;
	red.name = "red";
	red.colour = {255, 0, 0};
	blue.name = "blue";
	blue.colour = {0, 0, 255};
	for (int i = 0; i <= 100; i++)
	{
		red.points.push_back({0, 0, double(i)});	// camera frame: straight ahead
		blue.points.push_back({20, 0, double(i)});	// 20 m to the right
	}
	SnapshotOptions o;
	o.width = 400;
	o.height = 300;
	o.grid = false;
	o.marginFraction = 0.1;
	o.legendBand = false;  // the projection alone decides where the paths go
	renderTrajectories({red, blue}, o, dir + "/snap.png");
	const cv::Mat img = cv::imread(dir + "/snap.png");
	ASSERT_EQ(img.cols, 400);
	ASSERT_EQ(img.rows, 300);
	// Extent 100 m across 80% of 400 px: 0.3125 m/px; centre between the paths.
	// red (x=0) is 10 m = 32 px above the centre row, blue 32 px below.
	const int cx = 200, cy = 150;
	EXPECT_TRUE(isRed(img.at<cv::Vec3b>(cy - 32, cx))) << img.at<cv::Vec3b>(cy - 32, cx);
	EXPECT_TRUE(isBlue(img.at<cv::Vec3b>(cy + 32, cx))) << img.at<cv::Vec3b>(cy + 32, cx);
	EXPECT_EQ(img.at<cv::Vec3b>(cy, cx), cv::Vec3b(255, 255, 255));
	// Paths start at the left margin (40 px) and end at the right one (360 px).
	EXPECT_TRUE(isRed(img.at<cv::Vec3b>(cy - 32, 45)));
	EXPECT_FALSE(isRed(img.at<cv::Vec3b>(cy - 32, 30)));
	EXPECT_TRUE(isRed(img.at<cv::Vec3b>(cy - 32, 355)));
	EXPECT_FALSE(isRed(img.at<cv::Vec3b>(cy - 32, 370)));
}

TEST(RenderSnapshot, NothingToDrawIsAnErrorAndWritesNothing)
{
	const auto dir = shadyloc::test::tempDir("render_bad");
	EXPECT_THROW(renderTrajectories({}, {}, dir + "/x.png"), std::runtime_error);
	EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}

TEST(RenderSnapshot, AppRendersTumFilesAndRejectsBadOnes)
{
	const auto dir = shadyloc::test::tempDir("render_app");
	{
		std::ofstream f(dir + "/a.tum");
		for (int i = 0; i < 20; i++) f << i << " " << 0.1 * i * i << " 0 " << i << " 0 0 0 1\n";
		std::ofstream g(dir + "/bad.tum");
		g << "0 1 2\n";
	}
	std::string out;
	ASSERT_EQ(shadyloc::test::runCommand(shadyloc::test::appPath() + " render -t " + dir + "/a.tum:gt -o " + dir + "/a.png --width 320 --height 200", &out), 0) << out;
	const cv::Mat img = cv::imread(dir + "/a.png");
	EXPECT_EQ(img.cols, 320);
	EXPECT_EQ(img.rows, 200);
	EXPECT_NE(shadyloc::test::runCommand(shadyloc::test::appPath() + " render -t " + dir + "/bad.tum -o " + dir + "/b.png", &out), 0);
	EXPECT_NE(out.find("bad.tum"), std::string::npos) << out;
	EXPECT_FALSE(std::filesystem::exists(dir + "/b.png"));
}

// --align draws an estimate in the first trajectory's frame: a copy of the
// ground truth moved by a rigid transform then lies exactly on it (the red
// copy, drawn on top, hides the black truth), and not without --align.
TEST(RenderSnapshot, AppAlignsEstimatesToTheFirstTrajectory)
{
	const auto dir = shadyloc::test::tempDir("render_align");
	{
		std::ofstream gt(dir + "/gt.tum"), moved(dir + "/moved.tum");
		for (int i = 0; i < 40; i++)
		{
			const double x = i, y = 0.05 * i * i;
			gt << i << " " << x << " " << y << " 0 0 0 0 1\n";
			// rotated 90 deg about z (quaternion (0,0,s,s)) and shifted
			moved << i << " " << -y + 5 << " " << x - 3 << " 2 0 0 0.7071067812 0.7071067812\n";
		}
	}
	auto blackPixels = [&](const std::string& extra) {
		std::string out;
		EXPECT_EQ(shadyloc::test::runCommand(shadyloc::test::appPath() + " render --width 300 --height 200 -t " + dir +
											  "/gt.tum -t " + dir + "/moved.tum -o " + dir + "/a.png " + extra, &out), 0)
			<< out;
		const cv::Mat img = cv::imread(dir + "/a.png");
		int n = 0;
		for (int y = 80; y < img.rows; y++)	// below the legend (two 21 px lines from 24 px)
			for (int x = 0; x < img.cols; x++)
			{
				const auto p = img.at<cv::Vec3b>(y, x);
				n += p[0] < 60 && p[1] < 60 && p[2] < 60;
			}
		return n;
	};
	const int aligned = blackPixels("--align"), unaligned = blackPixels("");
	EXPECT_LT(aligned, 20) << "ground truth should be hidden under the aligned copy";
	EXPECT_GT(unaligned, 200);
}

// Any MRPT scene: auto framing puts a lone box in the middle of the picture
// whatever its coordinates; an explicit camera puts it where asked.
TEST(RenderSnapshot, SceneSnapshotFramesAnyScene)
{
	mrpt::opengl::COpenGLScene scene;
	scene.getViewport()->setCustomBackgroundColor({1.0f, 1.0f, 1.0f});
	// A red square, 4 m a side, 100 m and 200 m from the origin.
	auto box = mrpt::opengl::CSetOfTriangles::Create();
	const mrpt::math::TPoint3Df a(100, 200, 0), b(104, 200, 0), c(104, 204, 0), d(100, 204, 0);
	mrpt::opengl::TTriangle t1(a, b, c), t2(a, c, d);
	for (auto* t : {&t1, &t2})
		for (auto& v : t->vertices) v.setColor(mrpt::img::TColor(255, 0, 0));
	box->insertTriangle(t1);
	box->insertTriangle(t2);
	box->enableLight(false);
	scene.insert(box);
	const auto img = snapshotScene(scene, 200, 100).asCvMat<cv::Mat>(mrpt::img::DEEP_COPY);
	ASSERT_EQ(img.cols, 200);
	ASSERT_EQ(img.rows, 100);
	auto red = [](const cv::Mat& m, int x, int y) {
		const auto p = m.at<cv::Vec3b>(y, x);	// CImage stores BGR
		return p[2] > 180 && p[1] < 90 && p[0] < 90;
	};
	EXPECT_TRUE(red(img, 100, 50));
	EXPECT_FALSE(red(img, 5, 5));
	EXPECT_FALSE(red(img, 195, 95));
	// Looking at a point 30 m away from the box: it is out of the picture.
	TSceneCamera cam;
	cam.auto_frame = false;
	cam.pointing_at = {130, 200, 0};
	cam.zoom_distance = 20;
	const auto away = snapshotScene(scene, 200, 100, cam).asCvMat<cv::Mat>(mrpt::img::DEEP_COPY);
	EXPECT_FALSE(red(away, 100, 50));
	// Written atomically; an empty scene is an error and writes nothing.
	const auto dir = shadyloc::test::tempDir("render_scene");
	snapshotSceneToPng(scene, 200, 100, dir + "/box.png");
	EXPECT_EQ(cv::imread(dir + "/box.png").cols, 200);
	mrpt::opengl::COpenGLScene empty;
	EXPECT_THROW(snapshotSceneToPng(empty, 200, 100, dir + "/empty.png"), std::runtime_error);
	EXPECT_FALSE(std::filesystem::exists(dir + "/empty.png"));
}

// `render -m` draws a keyframe map through its getVisualizationInto: the
// measured path as a blue band, the part after the VO break in orange.
TEST(RenderSnapshot, AppDrawsKeyframeMaps)
{
	const auto dir = shadyloc::test::tempDir("render_map");
	shadyloc::test::makeSyntheticMap(30, 10, 20)->saveToFile(dir + "/m.kfmap");
	std::string out;
	ASSERT_EQ(shadyloc::test::runCommand(shadyloc::test::appPath() + " render -m " + dir + "/m.kfmap:synthetic -o " + dir +
										  "/m.png --width 400 --height 300", &out), 0)
		<< out;
	const cv::Mat img = cv::imread(dir + "/m.png");
	ASSERT_EQ(img.cols, 400);
	int blue = 0, orange = 0;
	for (int y = 60; y < img.rows; y++)	// below the legend
		for (int x = 0; x < img.cols; x++)
		{
			const auto p = img.at<cv::Vec3b>(y, x);
			blue += p[0] > 200 && p[1] > 100 && p[1] < 150 && p[2] < 100;
			orange += p[2] > 200 && p[1] > 110 && p[1] < 170 && p[0] < 60;
		}
	// 20 measured links and 9 predicted ones, each a band ~12 px wide.
	EXPECT_GT(blue, 1000);
	EXPECT_GT(orange, 300);
	// Nothing to render, a missing map, and the old name (still works, says so).
	EXPECT_NE(shadyloc::test::runCommand(shadyloc::test::appPath() + " render -o " + dir + "/x.png", &out), 0);
	EXPECT_NE(out.find("nothing to render"), std::string::npos) << out;
	EXPECT_NE(shadyloc::test::runCommand(shadyloc::test::appPath() + " render -m " + dir + "/none.kfmap -o " + dir + "/x.png", &out), 0);
	EXPECT_NE(out.find("none.kfmap"), std::string::npos) << out;
	EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
	ASSERT_EQ(shadyloc::test::runCommand(shadyloc::test::appPath() + " render-traj -m " + dir + "/m.kfmap -o " + dir + "/old.png", &out), 0)
		<< out;
	EXPECT_NE(out.find("renamed to `shadyloc render`"), std::string::npos) << out;
}

// `render --localised OUTDIR`: the live trajectory of a localise output
// folder coloured by frames.csv's `used` (blue mono, orange invariant, red
// none) over the map's keyframes in grey, and the live ground truth brought
// into the map frame through the keyframes' ground truth (black, on the
// keyframe chain here, since the live run drove it exactly).
TEST(RenderSnapshot, AppColoursALocalisedRunByItsLocaliser)
{
	const auto dir = shadyloc::test::tempDir("render_localised");
	// The world frame of the ground truth: the map frame moved and turned
	// (the keyframes' ground truth and the live run's are both in it).
	Eigen::Isometry3d T_world_map = Eigen::Isometry3d::Identity();
	T_world_map.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()).toRotationMatrix();
	T_world_map.translation() = Eigen::Vector3d(40, 1, -25);
	const auto src = shadyloc::test::makeSyntheticMap(30, 10, 0);
	auto map = shadyloc::CKeyframeMap::Create();
	map->options = src->options;
	map->setup(src->calibration(), src->imageWidth(), src->imageHeight(), src->channels());
	for (const auto& r : src->runs()) map->addRun(r);
	for (auto k : src->keyframes())
	{
		k.T_gt_kf = T_world_map * *k.T_gt_kf;
		map->appendKeyframe(k);
	}
	map->saveToFile(dir + "/m.kfmap");
	std::filesystem::create_directories(dir + "/loc");
	{
		std::ofstream csv(dir + "/loc/frames.csv"), tum(dir + "/loc/trajectory.tum"), gt(dir + "/gt.tum");
		csv << "frame,stamp,distance_m,in_map,mono_ok,invariant_ok,used\n";
		tum << std::fixed << std::setprecision(9);
		gt << std::fixed << std::setprecision(9);
		csv << std::fixed;
		const auto& kfs = map->keyframes();
		for (size_t i = 0; i < kfs.size(); i++)
		{
			// 10 frames mono, 10 invariant, 10 none; the estimate 4 m to the right of the truth.
			const char* used = i < 10 ? "mono" : (i < 20 ? "invariant" : "none");
			const double t = 500.0 + 0.1 * i;
			csv << i << ',' << std::setprecision(6) << t << ',' << 2.0 * i << ",1," << int(i < 10) << ','
				<< int(i >= 10 && i < 20) << ',' << used << '\n';
			const Eigen::Vector3d est = kfs[i].T_map_kf * Eigen::Vector3d(4, 0, 0);
			tum << t << ' ' << est.x() << ' ' << est.y() << ' ' << est.z() << " 0 0 0 1\n";
			const Eigen::Vector3d g = kfs[i].T_gt_kf->translation();
			gt << t << ' ' << g.x() << ' ' << g.y() << ' ' << g.z() << " 0 0 0 1\n";
		}
	}
	std::string out;
	ASSERT_EQ(shadyloc::test::runCommand(shadyloc::test::appPath() + " render -m " + dir + "/m.kfmap:synthetic --localised " +
										  dir + "/loc --gt " + dir + "/gt.tum -o " + dir + "/l.png --width 600 --height 500",
										  &out),
			  0)
		<< out;
	const cv::Mat img = cv::imread(dir + "/l.png");
	ASSERT_EQ(img.cols, 600);
	// Below the legend band (no title, 5 legend lines of 21 px from 24 px down).
	const int y0 = 150;
	size_t blue = 0, orange = 0, red = 0, black = 0, blackOnChain = 0;
	auto near = [&](int x, int y, const cv::Vec3b& c) {
		for (int dy = -4; dy <= 4; dy++)
			for (int dx = -4; dx <= 4; dx++)
			{
				const int u = x + dx, v = y + dy;
				if (u >= 0 && v >= 0 && u < img.cols && v < img.rows && img.at<cv::Vec3b>(v, u) == c) return true;
			}
		return false;
	};
	for (int y = y0; y < img.rows; y++)
		for (int x = 0; x < img.cols; x++)
		{
			const auto p = img.at<cv::Vec3b>(y, x);
			blue += p == cv::Vec3b(196, 98, 31);
			orange += p == cv::Vec3b(14, 130, 230);
			red += p == cv::Vec3b(40, 39, 214);
			if (p[0] < 40 && p[1] < 40 && p[2] < 40)
			{
				black++;
				blackOnChain += near(x, y, cv::Vec3b(150, 150, 150));
			}
		}
	// Segments end at frames 1-9 (mono), 10-19 (invariant), 20-29 (none): 9:10:10.
	ASSERT_GT(blue, 300u);
	EXPECT_NEAR(double(orange) / blue, 10.0 / 9.0, 0.15);
	EXPECT_NEAR(double(red) / blue, 10.0 / 9.0, 0.15);
	EXPECT_GT(black, 100u);
	EXPECT_GT(blackOnChain, 0.95 * black) << "the ground truth is not on the keyframe chain";

	// A trajectory.tum whose poses have no frame in frames.csv: refused, nothing written.
	std::filesystem::create_directories(dir + "/other");
	std::filesystem::copy_file(dir + "/loc/frames.csv", dir + "/other/frames.csv");
	std::ofstream(dir + "/other/trajectory.tum") << "900.0 0 0 0 0 0 0 1\n901.0 1 0 0 0 0 0 1\n";
	EXPECT_NE(shadyloc::test::runCommand(shadyloc::test::appPath() + " render --localised " + dir + "/other -o " + dir + "/x.png", &out), 0);
	EXPECT_NE(out.find("has no frame in"), std::string::npos) << out;
	EXPECT_NE(shadyloc::test::runCommand(shadyloc::test::appPath() + " render --localised " + dir + "/nowhere -o " + dir + "/x.png", &out), 0);
	EXPECT_NE(out.find("nowhere"), std::string::npos) << out;
	EXPECT_NE(shadyloc::test::runCommand(shadyloc::test::appPath() + " render --localised " + dir + "/loc --gt " + dir + "/gt.tum -o " + dir + "/x.png", &out), 0);
	EXPECT_NE(out.find("--gt needs --localised and a map"), std::string::npos) << out;
	EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}
