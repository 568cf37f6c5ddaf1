/* Simulator geometry and output: markers placed at known points appear where
 * the written calibration and ground truth project them, with disparity
 * f*b/Z; the rawlog carries what a reader needs; rendering is deterministic. */
#include "../support/Sequences.h"
#include "../support/TestSupport.h"

#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/sim/StereoSimulator.h>

#include <gtest/gtest.h>

#include <mrpt/math/CQuaternion.h>
#include <mrpt/poses/CPose3DQuat.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <sstream>

using namespace shadyloc::sim;

namespace
{
using shadyloc::test::smallSimOptions;

/** Centroid of purple (marker-coloured) pixels within radius r of (u, v). */
bool purpleCentroid(const cv::Mat& bgr, double u, double v, double r, double& cu, double& cv_, int& n)
{
	double su = 0, sv = 0;
	n = 0;
	for (int y = std::max(0, int(v - r)); y <= std::min(bgr.rows - 1, int(v + r)); y++)
		for (int x = std::max(0, int(u - r)); x <= std::min(bgr.cols - 1, int(u + r)); x++)
		{
			const auto& p = bgr.at<cv::Vec3b>(y, x);
			// Marker: strong blue and red, weak green. No other material is
			// (sky: red weak; brick: blue weak; foliage: green strong).
			if (p[0] > 1.6 * p[1] + 4 && p[2] > 1.6 * p[1] + 4)
			{
				su += x, sv += y;
				n++;
			}
		}
	if (n == 0) return false;
	cu = su / n, cv_ = sv / n;
	return true;
}
}  // namespace

// Must-show 2: render markers at known world points; read the rawlog and TUM
// back; project with the stored calibration and pose; the marker is there to
// a fraction of a pixel, and its right-image disparity is f*b/Z.
TEST(SimGeometry, MarkersProjectWhereGroundTruthSays)
{
	auto o = smallSimOptions(320, 240);
	o.traversals = {o.traversal("noon")};
	o.traversals[0].frames = 6;
	o.traversals[0].start_s_m = 230;  // the open stretch: nothing tall near the road
	o.traversals[0].lateral_offset_m = 0;
	const int kFrame = 4;
	// Marker positions chosen in the left camera of frame 4 (x right, y down,
	// z forward; m; images > 25 px apart, all above the road), then put in the world through the
	// simulator's pose.
	const std::vector<mrpt::math::TPoint3D> inCam = {{0.3, -0.1, 7.0}, {-1.5, -0.3, 12.0}, {1.0, -2.5, 20.0}};
	std::vector<mrpt::math::TPoint3D> world;
	{
		StereoSimulator probe(o);
		const auto T = probe.T_world_left(kFrame);
		for (const auto& p : inCam)
		{
			world.push_back(T.composePoint(p));
			// Radius 0.04 Z: every marker spans ~10 px of radius at f = 251 px.
			o.scene.markers.push_back({world.back().x, world.back().y, world.back().z, 0.04 * p.z});
		}
	}
	const std::string dir = shadyloc::test::tempDir("sim_geometry");
	StereoSimulator sim(o);
	sim.generate(dir + "/g.rawlog", dir + "/g.tum");

	const auto tum = shadyloc::io::readTum(dir + "/g.tum");
	ASSERT_EQ(tum.size(), 6u);
	shadyloc::io::RawlogReader reader(dir + "/g.rawlog");
	mrpt::obs::CObservationStereoImages::Ptr obs;
	for (int i = 0; i <= kFrame; i++)
	{
		auto o2 = reader.next();
		ASSERT_TRUE(o2);
		obs = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(o2);
		ASSERT_TRUE(obs);
	}
	EXPECT_NEAR(mrpt::Clock::toDouble(obs->timestamp), tum[kFrame].t, 1e-4);
	const auto& K = obs->leftCamera;
	const double b = obs->rightCameraPose.x();
	EXPECT_NEAR(b, 0.12, 1e-9);
	const cv::Mat left = obs->imageLeft.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY);
	const cv::Mat right = obs->imageRight.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY);
	ASSERT_EQ(left.type(), CV_8UC3);

	const mrpt::poses::CPose3D T_world_left = shadyloc::io::toCPose3D(tum[kFrame].T);
	// The renderer's own material labels, rendered from the pose read back
	// from the TUM file: free of the shading of the marker (its shadowed
	// lower half is darker, which biases the colour detection below by a
	// few tenths of a pixel).
	TRenderAux auxL, auxR;
	cv::Mat linL, linR;
	sim.renderLinear(T_world_left, linL, linR, &auxL, &auxR);
	auto labelCentroid = [](const cv::Mat& mat, double u, double v, double r, double& cu, double& cv_) {
		double su = 0, sv = 0;
		int n = 0;
		for (int y = std::max(0, int(v - r)); y <= std::min(mat.rows - 1, int(v + r)); y++)
			for (int x = std::max(0, int(u - r)); x <= std::min(mat.cols - 1, int(u + r)); x++)
				if (mat.at<uint8_t>(y, x) == kMarker) su += x, sv += y, n++;
		cu = n ? su / n : -1, cv_ = n ? sv / n : -1;
		return n;
	};
	for (const auto& pw : world)
	{
		const auto pc = T_world_left.inverseComposePoint(pw);  // marker in the left camera
		const double u = K.fx() * pc.x / pc.z + K.cx(), v = K.fy() * pc.y / pc.z + K.cy();
		const double rPx = K.fx() * 0.04;
		// A sphere's outline is an ellipse whose centre (= its area centroid)
		// lies off the projected sphere centre, outwards, by ~ offset * (r/Z)^2:
		// at angle theta off-axis with angular radius rho, the ellipse spans
		// f tan(theta - rho) .. f tan(theta + rho) along the radial direction.
		auto outlineCentre = [&](double X, double Y, double Z, double& eu, double& ev) {
			const double rad = std::hypot(X, Y), D = std::sqrt(X * X + Y * Y + Z * Z);
			const double theta = std::atan2(rad, Z), rho = std::asin(0.04 * Z / D);
			const double rc = 0.5 * K.fx() * (std::tan(theta + rho) + std::tan(theta - rho));
			eu = K.cx() + rc * X / rad;
			ev = K.cy() + rc * Y / rad;
		};
		double eu, ev, eru, erv;
		outlineCentre(pc.x, pc.y, pc.z, eu, ev);
		outlineCentre(pc.x - b, pc.y, pc.z, eru, erv);	// the right camera sees x - b
		double cu, cv_, ru, rv;
		int n, nr;
		ASSERT_TRUE(purpleCentroid(left, u, v, rPx + 3, cu, cv_, n)) << "no marker near (" << u << "," << v << ")";
		// A disc of radius rPx covers ~pi rPx^2 pixels; at least half of them
		// must be found (the rest may be anti-aliased edges or noise).
		EXPECT_GT(n, 0.5 * M_PI * rPx * rPx);
		// In the 8-bit image, found by colour: within half a pixel (shading
		// and noise decide which edge pixels pass the colour test; measured
		// bias up to 0.35 px, from the darker lower half of the sphere).
		// The projected centre lands on the marker. The colour centroid is
		// biased upwards: the sphere's lower half faces the ground, gets no
		// sky light (v_sky = (1 + n_z)/2) and is too dark to pass the colour
		// test (measured 0.5-1.4 px); horizontally it is within half a pixel.
		{
			const auto& c = left.at<cv::Vec3b>(int(std::lround(v)), int(std::lround(u)));
			EXPECT_TRUE(c[0] > 1.6 * c[1] && c[2] > 1.6 * c[1]) << "projection not on the marker";
		}
		EXPECT_NEAR(cu, eu, 0.5);
		EXPECT_NEAR(cv_, ev, 2.0);
		// Right image: same row, shifted by the disparity f*b/Z.
		const double disparity = K.fx() * b / pc.z;
		ASSERT_TRUE(purpleCentroid(right, u - disparity, v, rPx + 3, ru, rv, nr));
		EXPECT_NEAR(cu - ru, disparity + (eu - u) - (eru - (u - disparity)), 0.3) << "Z = " << pc.z;
		EXPECT_NEAR(rv, cv_, 0.5);
		// Label centroids: pure geometry. Sampling a disc of radius R px at
		// pixel centres misplaces its centroid by the count imbalance of its
		// ~2 pi R boundary pixels: ~sqrt(2 pi R)/3 pixels at distance R over
		// pi R^2 ~ 0.5/sqrt(R) px at most, typically far less: 0.15 px at R = 10.
		double lu, lv, lru, lrv;
		// Unoccluded: the full disc (~pi R^2 = 314 px) is found.
		ASSERT_GT(labelCentroid(auxL.material, u, v, rPx + 3, lu, lv), 0.95 * M_PI * rPx * rPx);
		ASSERT_GT(labelCentroid(auxR.material, u - disparity, v, rPx + 3, lru, lrv), 0.95 * M_PI * rPx * rPx);
		EXPECT_NEAR(lu, eu, 0.15);
		EXPECT_NEAR(lv, ev, 0.15);
		EXPECT_NEAR(lru, eru, 0.15);
		EXPECT_NEAR(lrv, erv, 0.15);
		// Disparity of the centres: f*b/Z exactly; of the outlines, up to
		// the (different) outline offsets of the two eyes.
		EXPECT_NEAR(lu - lru, disparity + (eu - u) - (eru - (u - disparity)), 0.3);  // two eyes' errors
		std::cout << "marker Z " << pc.z << " m, labels: centroid - outline centre L (" << lu - eu << ", "
				  << lv - ev << ") R (" << lru - eru << ", " << lrv - erv << ") px; centre disparity f*b/Z "
				  << disparity << " px\n";
		std::cout << "marker Z " << pc.z << " m: colour centroid - outline centre (" << cu - eu << ", " << cv_ - ev
				  << ") px, disparity " << cu - ru << " vs f*b/Z " << disparity << " px\n";
	}
}

// The rig: left camera 1.5 m above the ground, baseline/2 left of the
// vehicle's centre, looking along the route (optical axis ~ horizontal).
TEST(SimGeometry, CameraMountAndConventions)
{
	auto o = smallSimOptions(64, 48);
	StereoSimulator sim(o);
	const auto T = sim.T_world_left(0);
	EXPECT_NEAR(T.z(), 1.5, 1e-9);
	// Camera z axis (forward) is the third rotation column; tilted down by
	// pitch_deg = 3: its world z component is -sin(3 deg).
	const auto R = T.getRotationMatrix();
	EXPECT_NEAR(R(2, 2), -std::sin(3.0 * M_PI / 180), 1e-9);
	// Camera y (down) points mostly to world -z.
	EXPECT_LT(R(2, 1), -0.99);
	// The right camera is baseline along the left camera's x axis.
	const auto Tr = T + sim.T_left_right();
	const mrpt::math::TPoint3D xAxis(R(0, 0), R(1, 0), R(2, 0));
	EXPECT_NEAR((Tr.x() - T.x()) / 0.12, xAxis.x, 1e-9);
	EXPECT_NEAR((Tr.y() - T.y()) / 0.12, xAxis.y, 1e-9);
	// Consecutive frames advance ~speed/fps along the camera's forward axis.
	const auto T1 = sim.T_world_left(1);
	const double step = std::hypot(T1.x() - T.x(), T1.y() - T.y());
	const double v = o.traversals.front().speed_mps;
	EXPECT_GT(step, 0.7 * v / o.camera.fps);  // speed_variation 0.2: within +-20%
	EXPECT_LT(step, 1.3 * v / o.camera.fps);
}

// Same seeds, same frame -> same bytes; another wind seed moves the leaves
// (only canopy-affected pixels change); overcast has no sun at all.
TEST(SimGeometry, DeterministicAndSeedsMatter)
{
	auto o = smallSimOptions(128, 96);
	StereoSimulator a(o), b(o);
	auto t = o.traversal("noon");
	t.start_s_m = 20;  // under the trees
	a.setTraversal(t);
	b.setTraversal(t);
	TRenderAux aux;
	const TSimFrame fa = a.renderFrame(3, &aux), fb = b.renderFrame(3);
	EXPECT_EQ(cv::norm(fa.left, fb.left, cv::NORM_INF), 0.0);
	EXPECT_EQ(cv::norm(fa.right, fb.right, cv::NORM_INF), 0.0);
	t.wind_seed += 100;
	b.setTraversal(t);
	TRenderAux auxWind;
	b.renderFrame(3, &auxWind);
	cv::Mat diff;
	cv::absdiff(aux.sun, auxWind.sun, diff);
	EXPECT_GT(cv::countNonZero(diff > 0.5f), 20) << "wind must move the dappled light";
	b.setTraversal(o.traversal("overcast"));
	TRenderAux auxOver;
	b.renderFrame(3, &auxOver);
	EXPECT_EQ(cv::countNonZero(auxOver.sun > 0), 0);
}

// The options dump is itself a valid sim.ini that loads back to the same options.
TEST(SimOptions, DumpLoadsBackIdentically)
{
	const auto o = TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	std::ostringstream a;
	o.dumpToTextStream(a);
	const std::string path = shadyloc::test::tempDir("sim_options") + "/dump.ini";
	std::ofstream(path) << a.str();
	const auto o2 = TSimOptions::FromFile(path);
	std::ostringstream b;
	o2.dumpToTextStream(b);
	EXPECT_EQ(a.str(), b.str());
	ASSERT_EQ(o2.traversals.size(), 4u);
	EXPECT_TRUE(o2.traversal("overcast").overcast);
	EXPECT_EQ(o2.camera.width, 512);
	EXPECT_THROW(o2.traversal("dusk"), SimOptionsError);
}

// The default traversals cover one common stretch: they start at the same
// route position and end at their first frame at or past end_s_m, so their
// last frames lie within one frame's travel of each other, whatever their
// speeds (7.5-8.5 m/s, +-20 %).
TEST(SimOptions, DefaultTraversalsCoverOneStretch)
{
	auto o = TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	o.camera.width = 64;  // no rendering here: a small camera builds quickly
	o.camera.height = 48;
	ASSERT_EQ(o.traversals.size(), 4u);
	StereoSimulator sim(o);
	const double start = o.traversals.front().start_s_m, end = o.traversals.front().end_s_m;
	EXPECT_GE(end - start, 60.0) << "long enough to show failures and recoveries";
	EXPECT_LE(end, o.scene.route_length_m) << "the default stretch lies on the route";
	double firstEnd = 1e9, lastEnd = -1e9, maxStep = 0;
	for (const auto& t : o.traversals)
	{
		ASSERT_TRUE(t.endsByDistance()) << t.name;
		EXPECT_EQ(t.start_s_m, start) << t.name;
		EXPECT_EQ(t.end_s_m, end) << t.name;
		sim.setTraversal(t);
		const int n = sim.frameCount();
		ASSERT_GE(n, 2) << t.name;
		EXPECT_EQ(sim.routePosition(0), start) << t.name;
		for (int i = 1; i < n; i++)
		{
			const double step = sim.routePosition(i) - sim.routePosition(i - 1);
			ASSERT_GT(step, 0) << t.name << " frame " << i;
			maxStep = std::max(maxStep, step);
		}
		EXPECT_GE(sim.routePosition(n - 1), end) << t.name;
		EXPECT_LT(sim.routePosition(n - 2), end) << t.name;
		firstEnd = std::min(firstEnd, sim.routePosition(n - 1));
		lastEnd = std::max(lastEnd, sim.routePosition(n - 1));
	}
	EXPECT_LT(lastEnd - firstEnd, maxStep) << "last frames between " << firstEnd << " and " << lastEnd << " m";
	EXPECT_LT(maxStep, 1.2 * 8.5 / o.camera.fps + 1e-9);
}
