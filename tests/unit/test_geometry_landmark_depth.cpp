/* ShadyLoc — a landmark's depth refined by its re-observations
 * (geometry/LandmarkDepth.h) and the two-view solve that uses it. */
#include <shadyloc/geometry/LandmarkDepth.h>
#include <shadyloc/geometry/PoseSolver.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace shadyloc::geometry;

namespace
{
TStereoCalib calib()
{
	TStereoCalib c;
	c.fx = c.fy = 402;
	c.cx = 256;
	c.cy = 192;
	c.cxR = 256;
	c.baseline = 0.12;
	return c;
}

bool inImage(const Eigen::Vector3d& z) { return z.x() >= 0 && z.x() < 512 && z.y() >= 0 && z.y() < 384 && z.z() >= 0; }

/** A survey's view of one landmark: the keyframe at the origin, frames every
 * 0.75 m along the optical axis up to 3 m before and after (a car driving
 * forward), each measurement with Gaussian pixel noise. */
struct TSurveyedLandmark
{
	Eigen::Vector3d z_kf;
	std::vector<TDepthObservation> obs;
	double D_true = 0;
};

TSurveyedLandmark surveyLandmark(const Eigen::Vector3d& P, double noise_px, std::mt19937& rng)
{
	const TStereoCalib c = calib();
	std::normal_distribution<double> n(0, noise_px);
	const auto noisy = [&](const Eigen::Vector3d& z) -> Eigen::Vector3d { return z + Eigen::Vector3d(n(rng), n(rng), n(rng)); };
	TSurveyedLandmark s;
	s.z_kf = noisy(c.project(P));
	s.D_true = c.fx * c.baseline / P.z();
	for (int k = -4; k <= 4; k++)
	{
		if (k == 0) continue;
		TDepthObservation o;
		o.T_obs_kf = Eigen::Translation3d(0, 0, -0.75 * k) * Eigen::AngleAxisd(0.002 * k, Eigen::Vector3d::UnitY());
		const Eigen::Vector3d p = o.T_obs_kf * P;
		if (p.z() < 1) continue;
		o.z = noisy(c.project(p));
		if (inImage(o.z)) s.obs.push_back(o);
	}
	return s;
}
}  // namespace

// Landmarks 8-40 m ahead, seen by the keyframe's 0.12 m stereo pair and by
// the survey frames 3 m either side: the refined disparity is several times
// closer to the truth than the pair's, and its sigma says how close (the
// normalised errors are not larger than the model claims).
TEST(GeometryLandmarkDepth, ReobservationsNarrowTheDepthAndItsSigmaHolds)
{
	std::mt19937 rng(7);
	std::uniform_real_distribution<double> ux(-0.55, 0.55), uy(-0.3, 0.3), uz(8, 40);
	const double noise = 0.4;
	TDepthRefinementOptions o;
	o.sigma_px = o.reobservation_sigma_px = noise;
	double ss0 = 0, ss1 = 0, nees = 0;
	int n = 0, within3 = 0, tried = 0;
	for (; n < 400 && tried < 4000; tried++)
	{
		const double Z = uz(rng);
		const auto s = surveyLandmark(Eigen::Vector3d(ux(rng) * Z, uy(rng) * Z, Z), noise, rng);
		if (!inImage(s.z_kf)) continue;
		const auto r = refineDisparity(calib(), s.z_kf, s.obs, o);
		if (!r.ok) continue;
		n++;
		const double e0 = s.z_kf.x() - s.z_kf.z() - s.D_true, e1 = r.disparity - s.D_true;
		ss0 += e0 * e0;
		ss1 += e1 * e1;
		nees += e1 * e1 / (r.sigma_disparity * r.sigma_disparity);
		within3 += std::abs(e1) <= 3 * r.sigma_disparity;
		EXPECT_GE(r.used, o.min_observations);
		EXPECT_LT(r.sigma_disparity, std::sqrt(2.0) * noise);
	}
	std::printf("refined %d of %d landmarks in view\n", n, tried);
	ASSERT_EQ(n, 400) << "most landmarks in view should be refined";
	const double rms0 = std::sqrt(ss0 / n), rms1 = std::sqrt(ss1 / n);
	std::printf("disparity rms: the pair %.3f px, refined %.3f px; mean NEES %.2f; within 3 sigma %d of %d\n", rms0, rms1,
				nees / n, within3, n);
	EXPECT_LT(rms1, 0.4 * rms0);
	// Not over-confident: the mean NEES of a consistent estimate is 1 (400
	// samples: 1 +- 0.07 at one sigma; the Huber weights and the linearisation
	// move it a little).
	EXPECT_GT(nees / n, 0.7);
	EXPECT_LT(nees / n, 1.3);
	EXPECT_GE(within3, static_cast<int>(0.97 * n));
}

// One re-observation 15 px off (a wrong match) is left out: the result is
// the one without it, to a fraction of its sigma.
TEST(GeometryLandmarkDepth, AWrongReobservationIsLeftOut)
{
	std::mt19937 rng(11);
	const auto s = surveyLandmark(Eigen::Vector3d(-6, 1, 20), 0.3, rng);
	ASSERT_GE(s.obs.size(), 6u);
	TDepthRefinementOptions o;
	o.sigma_px = o.reobservation_sigma_px = 0.3;
	const auto clean = refineDisparity(calib(), s.z_kf, s.obs, o);
	auto bad = s.obs;
	bad[2].z += Eigen::Vector3d(15, -4, 15);
	const auto r = refineDisparity(calib(), s.z_kf, bad, o);
	ASSERT_TRUE(clean.ok && r.ok);
	EXPECT_EQ(r.used, clean.used - 1);
	EXPECT_LT(std::abs(r.disparity - clean.disparity), 0.5 * clean.sigma_disparity);
	EXPECT_LT(std::abs(r.disparity - s.D_true), 3 * r.sigma_disparity);
}

// Too few re-observations, or re-observations that all place the landmark
// at twice the pair's depth (a wrong stereo match, or another surface):
// no refinement, the pair's depth stays.
TEST(GeometryLandmarkDepth, TooFewOrContradictingReobservationsKeepThePairsDepth)
{
	std::mt19937 rng(13);
	const Eigen::Vector3d P(-5, 0.5, 15);
	const auto s = surveyLandmark(P, 0.2, rng);
	TDepthRefinementOptions o;
	o.sigma_px = o.reobservation_sigma_px = 0.2;
	ASSERT_TRUE(refineDisparity(calib(), s.z_kf, s.obs, o).ok);
	EXPECT_FALSE(refineDisparity(calib(), s.z_kf, {s.obs.front()}, o).ok);
	EXPECT_FALSE(refineDisparity(calib(), s.z_kf, {}, o).ok);
	// The frames see the point at twice the depth along the same ray.
	auto far = surveyLandmark(2 * P, 0.2, rng);
	EXPECT_FALSE(refineDisparity(calib(), s.z_kf, far.obs, o).ok);
}

// The two-view solve of a camera 1.75 m aside (half a lane): with each
// landmark's refined disparity weighed by its sigma the pose is found as
// exactly, and its covariance is much smaller than with the pair's noise,
// where every landmark's depth is free to move by its stereo uncertainty.
TEST(GeometryLandmarkDepth, ARefinedDisparityNarrowsTheTwoViewSolve)
{
	const TStereoCalib c = calib();
	const Eigen::Isometry3d T_curr_ref =
		(Eigen::Translation3d(1.75, 0, 0.3) * Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY())).inverse();
	std::mt19937 rng(17);
	std::uniform_real_distribution<double> ux(-0.5, 0.5), uy(-0.3, 0.3), uz(6, 35);
	std::vector<TStereoCorrespondence> pair, refined;
	while (pair.size() < 60)
	{
		const double Z = uz(rng);
		const Eigen::Vector3d P(ux(rng) * Z, uy(rng) * Z, Z);
		const Eigen::Vector3d p = T_curr_ref * P;
		if (p.z() < 1 || !inImage(c.project(p)) || !inImage(c.project(P))) continue;
		TStereoCorrespondence k;
		k.z_ref = c.project(P);
		Eigen::Matrix3d J;
		ASSERT_TRUE(c.triangulate(k.z_ref.x(), k.z_ref.y(), k.z_ref.z(), k.P_ref, &J));
		k.cov_ref = c.triangulationCovariance(J, 0.5);
		k.calib_ref = c;
		k.z_curr = c.project(p);
		ASSERT_TRUE(c.triangulate(k.z_curr.x(), k.z_curr.y(), k.z_curr.z(), k.P_curr));
		pair.push_back(k);
		k.sigma_disparity_ref = 0.05;
		k.cov_ref = c.triangulationCovariance(J, 0.5, 0.05);
		refined.push_back(k);
	}
	TPoseSolverOptions so;
	so.sigma_px = 0.5;
	Eigen::Isometry3d T0 = T_curr_ref;
	T0.translation() += Eigen::Vector3d(0.05, -0.02, 0.1);
	const auto a = solveStereoPoseTwoView(c, pair, {}, T0, so);
	const auto b = solveStereoPoseTwoView(c, refined, {}, T0, so);
	ASSERT_TRUE(a.ok && b.ok);
	EXPECT_LT((a.T_curr_ref.translation() - T_curr_ref.translation()).norm(), 1e-5);
	EXPECT_LT((b.T_curr_ref.translation() - T_curr_ref.translation()).norm(), 1e-5);
	const double va = a.cov_T_ref_curr.topLeftCorner<3, 3>().trace(), vb = b.cov_T_ref_curr.topLeftCorner<3, 3>().trace();
	std::printf("translation sigma, 1.75 m aside: the pair's depths %.3f m, refined %.3f m\n", std::sqrt(va), std::sqrt(vb));
	EXPECT_LT(vb, 0.25 * va);
}

// The covariance of a measurement whose disparity was refined: uR = uL +
// doffs - D with uL, v, D independent; without a refined sigma, the pair's
// isotropic model to the bit.
TEST(GeometryLandmarkDepth, MeasurementCovarianceOfARefinedDisparity)
{
	const Eigen::Matrix3d C = TStereoCalib::measurementCovariance(0.5, 0.1);
	EXPECT_DOUBLE_EQ(C(0, 0), 0.25);
	EXPECT_DOUBLE_EQ(C(0, 2), 0.25);
	EXPECT_DOUBLE_EQ(C(2, 2), 0.25 + 0.01);
	// The disparity's variance: var(uL - uR) = sigma_D^2.
	const Eigen::Vector3d d(1, 0, -1);
	EXPECT_NEAR(d.dot(C * d), 0.01, 1e-15);
	const TStereoCalib c = calib();
	Eigen::Vector3d P;
	Eigen::Matrix3d J;
	ASSERT_TRUE(c.triangulate(300, 200, 296, P, &J));
	EXPECT_EQ(c.triangulationCovariance(J, 0.5, 0), c.triangulationCovariance(J, 0.5));
	// The depth's sigma follows the disparity's: Z = fx b / D.
	const double sz = std::sqrt(c.triangulationCovariance(J, 0.5, 0.1)(2, 2));
	EXPECT_NEAR(sz, P.z() / 4 * 0.1, 1e-9);
}
