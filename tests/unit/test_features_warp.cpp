/* Patches that follow the viewpoint (features/PatchWarp.h) and the surface
 * normals they need (features/SurfaceNormals.h). */
#include "../support/TestSupport.h"

#include <shadyloc/features/PatchWarp.h>
#include <shadyloc/features/SurfaceNormals.h>
#include <shadyloc/vo/KeyframeMatcher.h>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <random>

using namespace shadyloc;
using namespace shadyloc::features;

namespace
{
/** A smooth texture on the plane's coordinates (a, b) [m]: sinusoids of
 * 0.2-0.7 m wavelength (coarse enough not to alias at a few metres), grey
 * levels 30..225. */
double planeTexture(double a, double b)
{
	static const double k[6][3] = {{17, 5, 0.3}, {-7, 15, 1.1}, {9, -12, 2.0},
								   {21, 3, 0.7}, {-4, 24, 1.9}, {12, 19, 2.6}};
	double s = 0;
	for (const auto& w : k) s += std::sin(w[0] * a + w[1] * b + w[2]);
	return 127.5 + 16 * s;
}

/** The image of the road surface (the plane y = h below a camera looking
 * along +z, y down) from a camera at T_cam_world^-1 = T_world_cam. */
cv::Mat renderGround(const geometry::TStereoCalib& c, const Eigen::Isometry3d& T_world_cam, double h)
{
	cv::Mat img(384, 512, CV_8UC1, cv::Scalar(0));
	for (int v = 0; v < img.rows; v++)
		for (int u = 0; u < img.cols; u++)
		{
			const Eigen::Vector3d d = T_world_cam.linear() * Eigen::Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1);
			const Eigen::Vector3d o = T_world_cam.translation();
			if (d.y() <= 1e-6) continue;
			const Eigen::Vector3d X = o + (h - o.y()) / d.y() * d;
			img.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(planeTexture(X.x(), X.z()));
		}
	return img;
}

/** Where the ray of keyframe pixel (u, v) meets the plane n^T X = rho. */
Eigen::Vector3d onPlane(const geometry::TStereoCalib& c, double u, double v, const Eigen::Vector3d& n, double rho)
{
	const Eigen::Vector3d d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1);
	return rho / n.dot(d) * d;
}
}  // namespace

// The affine map is the derivative of the exact plane-to-plane map: pixel ->
// ray -> plane point -> other camera, by central differences.
TEST(FeaturesWarp, AffineIsTheDerivativeOfThePlaneInducedMap)
{
	const auto c = test::stereoCalib();
	const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.9, -0.3).normalized();
	const double rho = -1.4;  // n^T X = rho: the plane 1.4 m from the camera, facing it
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.3, 1, 0.1).normalized()).toRotationMatrix();
	T.translation() = Eigen::Vector3d(1.2, -0.1, -0.8);
	const double u = 300, v = 290;
	const Eigen::Vector3d P = onPlane(c, u, v, n, rho);
	ASSERT_GT(P.z(), 0);
	Eigen::Matrix2d A;
	ASSERT_TRUE(planeInducedAffine(c, c, T, P, n, A));
	auto image = [&](double uu, double vv) {
		const Eigen::Vector3d X = T * onPlane(c, uu, vv, n, rho);
		return Eigen::Vector2d(c.fx * X.x() / X.z() + c.cx, c.fy * X.y() / X.z() + c.cy);
	};
	const double h = 1e-3;
	Eigen::Matrix2d J;
	J.col(0) = (image(u + h, v) - image(u - h, v)) / (2 * h);
	J.col(1) = (image(u, v + h) - image(u, v - h)) / (2 * h);
	EXPECT_LT((A - J).cwiseAbs().maxCoeff(), 1e-5) << "A\n" << A << "\nfinite differences\n" << J;
	// The identity pose maps every plane onto itself.
	ASSERT_TRUE(planeInducedAffine(c, c, Eigen::Isometry3d::Identity(), P, n, A));
	EXPECT_LT(warpDistortion(A), 1e-12);
	// A plane seen edge-on from the other camera gives no warp.
	Eigen::Isometry3d edge = Eigen::Isometry3d::Identity();
	edge.translation() = Eigen::Vector3d(0, -P.y() + 1e-4, 0);	 // the camera moved into the ground plane's height
	EXPECT_FALSE(planeInducedAffine(c, c, edge, P, Eigen::Vector3d(0, -1, 0), A));
}

// With the identity the warped BRIEF pattern is the pattern itself.
TEST(FeaturesWarp, IdentityWarpGivesTheUnwarpedDescriptor)
{
	cv::Mat img(120, 160, CV_8UC1), smoothed;
	cv::randu(img, 0, 255);
	BriefExtractor::smooth(img, smoothed);
	const BriefExtractor brief(32, 0x5ad710c);
	const WarpedBriefPattern same(brief, Eigen::Matrix2d::Identity());
	int compared = 0;
	for (int y = 10; y < 110; y += 7)
		for (int x = 10; x < 150; x += 9)
		{
			TBriefDescriptor a, b;
			const bool okA = brief.compute(smoothed, x, y, a), okB = same.compute(smoothed, x, y, b);
			ASSERT_EQ(okA, okB) << x << "," << y;
			if (!okA) continue;
			EXPECT_EQ(a, b);
			compared++;
		}
	EXPECT_GT(compared, 50);
}

// The road surface seen from the survey and from half a lane (1.75 m) to the
// side: sheared by about 1.75 / 1.5 in the image. The keyframe's 9x9 patch,
// warped by the plane, is found within 0.3 px of its true position; as it
// is, it is not found at all or far off.
TEST(FeaturesWarp, WarpedPatchMatchesAPlaneSeenFromTwoViewpoints)
{
	const auto c = test::stereoCalib();
	const double h = 1.5;
	Eigen::Isometry3d T_world_kf = Eigen::Isometry3d::Identity(), T_world_live = Eigen::Isometry3d::Identity();
	T_world_live.translation() = Eigen::Vector3d(-1.75, 0, -0.3);
	const cv::Mat kfImg = renderGround(c, T_world_kf, h), liveImg = renderGround(c, T_world_live, h);
	const Eigen::Isometry3d T_live_kf = T_world_live.inverse() * T_world_kf;
	const Eigen::Vector3d n(0, -1, 0);	// the road, facing the camera above it
	int warpedRight = 0, unwarpedRight = 0, tried = 0;
	for (int u = 140; u <= 340; u += 40)
		for (int v = 270; v <= 330; v += 30)
		{
			const Eigen::Vector3d P = onPlane(c, u, v, n, n.dot(Eigen::Vector3d(0, h, 0)));
			std::array<uint8_t, kPatchSize * kPatchSize> patch{};
			for (int dy = -kPatchSize / 2; dy <= kPatchSize / 2; dy++)
				for (int dx = -kPatchSize / 2; dx <= kPatchSize / 2; dx++)
					patch[(dy + kPatchSize / 2) * kPatchSize + dx + kPatchSize / 2] = kfImg.at<uint8_t>(v + dy, u + dx);
			const Eigen::Vector3d X = T_live_kf * P;
			const Eigen::Vector2d truth(c.fx * X.x() / X.z() + c.cx, c.fy * X.y() / X.z() + c.cy);
			if (truth.x() < 24 || truth.y() < 24 || truth.x() > liveImg.cols - 24 || truth.y() > liveImg.rows - 24)
				continue;  // out of the live view
			// The search starts a pixel off, as from a prediction.
			const int x0 = static_cast<int>(std::lround(truth.x())) + 1, y0 = static_cast<int>(std::lround(truth.y()));
			Eigen::Matrix2d A;
			ASSERT_TRUE(planeInducedAffine(c, c, T_live_kf, P, n, A));
			EXPECT_GT(std::abs(A(0, 1)), 0.5) << "the test needs a strong shear";
			tried++;
			float x, y;
			if (locateWarpedPatch(patch, liveImg, x0, y0, A, 2, 0.6f, 5, x, y))
			{
				const double e = (Eigen::Vector2d(x, y) - truth).norm();
				EXPECT_LT(e, 0.3) << "at (" << u << ", " << v << ")";
				warpedRight += e < 0.3;
			}
			else
				ADD_FAILURE() << "warped patch not found at (" << u << ", " << v << ")";
			unwarpedRight += locatePatch(patch, liveImg, x0, y0, 2, 0.6f, 5, x, y) &&
							 (Eigen::Vector2d(x, y) - truth).norm() < 0.3;
		}
	ASSERT_GE(tried, 12);
	EXPECT_EQ(warpedRight, tried);
	EXPECT_EQ(unwarpedRight, 0);
}

// The normal of a plane from its disparity image: d = c + a du + b dv around
// the measurement, with some pixels missing and some from another surface.
TEST(FeaturesWarp, NormalFromTheDisparityOfATiltedPlane)
{
	const auto c = test::stereoCalib();
	const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.8, -0.5).normalized();
	const double rho = -4.0;
	cv::Mat disp(384, 512, CV_32F);
	std::mt19937 rng(3);
	std::uniform_real_distribution<double> U(0, 1);
	for (int v = 0; v < disp.rows; v++)
		for (int u = 0; u < disp.cols; u++)
		{
			const Eigen::Vector3d X = onPlane(c, u, v, n, rho);
			float d = static_cast<float>(c.fx * c.baseline / X.z() + 0.05 * (U(rng) - 0.5));
			const double r = U(rng);
			if (r < 0.1) d = std::numeric_limits<float>::quiet_NaN();  // no match
			else if (r < 0.15) d += 6.f;  // another surface
			disp.at<float>(v, u) = d;
		}
	TStereoMeasurement m;
	m.uL = 300;
	m.v = 250;
	m.P = onPlane(c, m.uL, m.v, n, rho);
	m.uR = static_cast<float>(m.uL - c.fx * c.baseline / m.P.z());
	std::vector<TStereoMeasurement> ms{m};
	TSurfaceNormalOptions o;
	ASSERT_EQ(estimateNormals(disp, c, o, ms), 1u);
	const double angle = std::acos(std::min(1.0, ms[0].normal.cast<double>().dot(n))) * 180 / M_PI;
	EXPECT_LT(angle, 3.0) << ms[0].normal.transpose();
	// A measurement whose own disparity the plane misses (it lies on another
	// surface) gets no normal.
	ms[0].uR -= 3.f;
	EXPECT_EQ(estimateNormals(disp, c, o, ms), 0u);
	EXPECT_TRUE(ms[0].normal.isZero());
}

// The localiser's second pass (KeyframeMatcher::searchPatches): landmarks of
// a keyframe (its corners on the road surface) seen from half a lane aside
// are found by their warped patches alone, with no live corner anywhere,
// three quarters within 0.5 px in the left image and in the right one, all
// within the solve's 3 px inlier bound (the strongest shear, at the image's
// edge, takes one to 2.9 px); skipped landmarks are not searched, and a live pixel holds
// one landmark at most.
TEST(VoKeyframeMatcher, PatchSearchFindsLandmarksWithoutCorners)
{
	const auto c = test::stereoCalib();
	const double h = 1.5;
	Eigen::Isometry3d T_world_kf = Eigen::Isometry3d::Identity(), T_world_live = Eigen::Isometry3d::Identity();
	T_world_live.translation() = Eigen::Vector3d(-1.75, 0, -0.3);
	Eigen::Isometry3d rightOf = Eigen::Isometry3d::Identity();
	rightOf.translation() = Eigen::Vector3d(c.baseline, 0, 0);
	const cv::Mat kfImg = renderGround(c, T_world_kf, h);
	features::TStereoFrame live;
	live.left = renderGround(c, T_world_live, h);
	live.right = renderGround(c, T_world_live * rightOf, h);
	BriefExtractor::smooth(live.left, live.smoothed);
	const Eigen::Isometry3d T_live_kf = T_world_live.inverse() * T_world_kf;
	const Eigen::Vector3d n(0, -1, 0);
	// The keyframe's landmarks are corners, as FAST gives them (a patch on
	// an edge is ambiguous along it).
	std::vector<cv::Point2f> corners;
	cv::goodFeaturesToTrack(kfImg(cv::Rect(120, 262, 240, 80)), corners, 60, 0.05, 12);
	std::vector<TStereoMeasurement> lms;
	for (const auto& p : corners)
	{
		const int u = 120 + static_cast<int>(std::lround(p.x)), v = 262 + static_cast<int>(std::lround(p.y));
		TStereoMeasurement m;
		m.uL = static_cast<float>(u);
		m.v = static_cast<float>(v);
		m.P = onPlane(c, u, v, n, n.dot(Eigen::Vector3d(0, h, 0)));
		m.uR = static_cast<float>(c.fx * (m.P.x() - c.baseline) / m.P.z() + c.cxR);
		m.cov = Eigen::Matrix3d::Identity() * 1e-4;
		m.normal = n.cast<float>();
		for (int dy = -kPatchSize / 2; dy <= kPatchSize / 2; dy++)
			for (int dx = -kPatchSize / 2; dx <= kPatchSize / 2; dx++)
				m.patch[(dy + kPatchSize / 2) * kPatchSize + dx + kPatchSize / 2] = kfImg.at<uint8_t>(v + dy, u + dx);
		lms.push_back(m);
	}
	vo::TKeyframeMatcherOptions o;
	o.warp = true;
	const vo::KeyframeMatcher matcher(o);
	const BriefExtractor brief(32, 0x5ad710c);
	vo::TKeyframeMatchInput in;
	in.landmarks = &lms;
	in.calib_kf = in.calib = c;
	in.frame = &live;
	in.brief = &brief;
	// A prediction a centimetre or two off, as a confirmed track gives.
	in.T_curr_kf_pred = T_live_kf;
	in.T_curr_kf_pred.translation() += Eigen::Vector3d(0.01, -0.005, 0.02);
	std::vector<uint8_t> skip(lms.size(), 0);
	skip[0] = skip[5] = 1;
	cv::Mat occupied = cv::Mat::zeros(live.left.size(), CV_8UC1);
	vo::TKeyframeMatchOutput out;
	matcher.searchPatches(in, skip, occupied, out);
	size_t visible = 0;
	for (size_t j = 0; j < lms.size(); j++)
	{
		const Eigen::Vector3d X = T_live_kf * lms[j].P;
		const double u = c.fx * X.x() / X.z() + c.cx, v = c.fy * X.y() / X.z() + c.cy;
		visible += !skip[j] && u > 30 && v > 30 && u < live.left.cols - 30 && v < live.left.rows - 30;
	}
	ASSERT_GE(visible, 15u);
	EXPECT_GE(out.corr.size(), visible * 8 / 10) << "of " << visible << " landmarks in view";
	EXPECT_EQ(out.warped, static_cast<int>(out.corr.size()));
	// A patch of a smooth surface's corner locates to a fraction of a pixel
	// most of the time; the rest stay inside the solve's inlier bound.
	size_t close = 0;
	for (size_t i = 0; i < out.corr.size(); i++)
	{
		const size_t j = static_cast<size_t>(out.landmark[i]);
		EXPECT_FALSE(skip[j]) << "a skipped landmark was searched";
		EXPECT_EQ(out.measurement[i], -1);
		const Eigen::Vector3d X = T_live_kf * lms[j].P;
		const Eigen::Vector3d truth(
			c.fx * X.x() / X.z() + c.cx, c.fy * X.y() / X.z() + c.cy, c.fx * (X.x() - c.baseline) / X.z() + c.cxR);
		const double e = (out.corr[i].z_curr - truth).cwiseAbs().maxCoeff();
		EXPECT_LT(e, 3.0) << "landmark " << j << ": " << out.corr[i].z_curr.transpose() << ", truth " << truth.transpose();
		close += e < 0.5;
	}
	EXPECT_GE(close, out.corr.size() * 3 / 4);
	// Searched again with the found pixels occupied: nothing more is found.
	vo::TKeyframeMatchOutput again;
	matcher.searchPatches(in, skip, occupied, again);
	EXPECT_TRUE(again.corr.empty());
}
