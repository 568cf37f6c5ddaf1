/* Tests of the VO's stages on their own: the keyframe matcher (circle and
 * covariance gate, sub-pixel refinement, the predicted measurement's
 * covariance), the relative-pose estimator (with and without the motion
 * prior), the keyframe policy, and StereoVO's track()/commit() split. */
#include "../support/TestSupport.h"

#include <shadyloc/filters/Channel.h>
#include <shadyloc/sim/SyntheticCorridor.h>
#include <shadyloc/vo/KeyframeMatcher.h>
#include <shadyloc/vo/KeyframePolicy.h>
#include <shadyloc/vo/RelativePoseEstimator.h>
#include <shadyloc/vo/StereoVO.h>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <Eigen/Eigenvalues>

#include <random>

using namespace shadyloc;
using geometry::Matrix6d;

namespace
{
Eigen::Isometry3d pose(double tx, double ty, double tz, double yawRad)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = Eigen::AngleAxisd(yawRad, Eigen::Vector3d::UnitY()).toRotationMatrix();
	T.translation() = Eigen::Vector3d(tx, ty, tz);
	return T;
}

features::TBriefDescriptor randomDesc(std::mt19937& rng)
{
	features::TBriefDescriptor d;
	for (auto& w : d.w) w = (uint64_t(rng()) << 32) ^ rng();
	return d;
}
features::TBriefDescriptor flipRandomBits(features::TBriefDescriptor d, int n, std::mt19937& rng)
{
	for (int i = 0; i < n; i++)
	{
		const unsigned b = rng() % 256;
		d.w[b / 64] ^= uint64_t(1) << (b % 64);
	}
	return d;
}

/** A keyframe and a current frame with known correspondences: the current
 * left image is smooth random texture; landmark j is seen at the continuous
 * position truth[j] (uL, v, uR) from T_curr_kf_true; its keyframe patch is
 * the current image sampled around truth[j] (so refinement must find
 * truth[j]), its current measurement is the integer corner next to it, with
 * the descriptor 10 bits away; distractors with random descriptors lie
 * 6-10 px from each true measurement. */
struct TScene
{
	geometry::TStereoCalib calib = test::stereoCalib();
	Eigen::Isometry3d T_curr_kf_true;
	std::vector<features::TStereoMeasurement> landmarks;
	features::TStereoFrame frame;
	std::vector<Eigen::Vector3d> truth;	 //!< per landmark
	std::vector<int> trueMeas;	//!< per landmark: index of its current measurement
};

TScene makeScene(const Eigen::Isometry3d& T_curr_kf, double depth, uint32_t seed)
{
	TScene s;
	s.T_curr_kf_true = T_curr_kf;
	std::mt19937 rng(seed);
	cv::Mat noise(384, 512, CV_32F);
	cv::randu(noise, 0, 255);
	cv::GaussianBlur(noise, noise, cv::Size(), 1.5);
	cv::normalize(noise, noise, 20, 235, cv::NORM_MINMAX);
	noise.convertTo(s.frame.left, CV_8U);
	std::uniform_real_distribution<double> frac(-0.45, 0.45), ang(0, 2 * M_PI), off(6, 10), dz(0, 0.5 * depth);
	for (int gy = 0; gy < 4; gy++)
		for (int gx = 0; gx < 6; gx++)
		{
			const double u = 60 + 78 * gx + frac(rng), v = 60 + 85 * gy + frac(rng);
			const double Z = depth + dz(rng);
			const double d = s.calib.fx * s.calib.baseline / Z;
			const Eigen::Vector3d z(u, v, u - d);
			Eigen::Vector3d P_curr;
			if (!s.calib.triangulate(z.x(), z.y(), z.z(), P_curr)) continue;
			features::TStereoMeasurement kf;
			kf.P = T_curr_kf.inverse() * P_curr;
			const Eigen::Vector3d zk = s.calib.project(kf.P);  // as measured in the keyframe
			kf.uL = static_cast<float>(zk.x());
			kf.v = static_cast<float>(zk.y());
			kf.uR = static_cast<float>(zk.z());
			kf.cov = 1e-4 * Eigen::Matrix3d::Identity();
			kf.desc = randomDesc(rng);
			cv::Mat patch;
			cv::getRectSubPix(s.frame.left, cv::Size(features::kPatchSize, features::kPatchSize), cv::Point2f(u, v), patch);
			std::copy(patch.datastart, patch.dataend, kf.patch.begin());
			s.truth.push_back(z);
			s.landmarks.push_back(kf);
			features::TStereoMeasurement m;
			m.uL = static_cast<float>(std::round(u));
			m.v = static_cast<float>(std::round(v));
			m.uR = static_cast<float>(m.uL - d);
			m.desc = flipRandomBits(kf.desc, 10, rng);
			s.trueMeas.push_back(static_cast<int>(s.frame.meas.size()));
			s.frame.meas.push_back(m);
			for (int k = 0; k < 2; k++)
			{
				const double a = ang(rng), r = off(rng);
				features::TStereoMeasurement x = m;
				x.uL = static_cast<float>(std::round(u + r * std::cos(a)));
				x.v = static_cast<float>(std::round(v + r * std::sin(a)));
				x.uR = static_cast<float>(x.uL - d);
				x.desc = randomDesc(rng);
				s.frame.meas.push_back(x);
			}
		}
	return s;
}

vo::TKeyframeMatchInput inputFor(const TScene& s, const Eigen::Isometry3d& T_pred)
{
	vo::TKeyframeMatchInput in;
	in.landmarks = &s.landmarks;
	in.calib_kf = s.calib;
	in.frame = &s.frame;
	in.calib = s.calib;
	in.T_curr_kf_pred = T_pred;
	return in;
}

/** Number of landmarks matched to their own measurement. */
int correctMatches(const TScene& s, const vo::TKeyframeMatchOutput& o)
{
	int n = 0;
	for (size_t i = 0; i < o.corr.size(); i++) n += o.measurement[i] == s.trueMeas[o.landmark[i]];
	return n;
}

Matrix6d poseCov(double sigma_t, double sigma_r)
{
	Matrix6d C = Matrix6d::Zero();
	C.diagonal() << Eigen::Vector3d::Constant(sigma_t * sigma_t), Eigen::Vector3d::Constant(sigma_r * sigma_r);
	return C;
}
}  // namespace

TEST(VoKeyframeMatcher, CircleFindsTrueMatchesAndRefinesToSubPixel)
{
	const auto s = makeScene(pose(0.05, -0.02, 0.3, 0.02), 6.0, 1);
	ASSERT_GE(s.landmarks.size(), 20u);
	vo::KeyframeMatcher m;
	vo::TKeyframeMatchOutput o;
	// The prediction is 3 cm off: a few pixels, well inside the 40 px circle.
	m.match(inputFor(s, pose(0.08, -0.02, 0.3, 0.02)), o);
	EXPECT_FALSE(o.widened);
	ASSERT_EQ(o.corr.size(), s.landmarks.size());
	EXPECT_EQ(correctMatches(s, o), static_cast<int>(o.corr.size()));
	double worst = 0;
	for (size_t i = 0; i < o.corr.size(); i++)
	{
		const auto& t = s.truth[o.landmark[i]];
		// uL and v from the patch; uR follows uL (the corner's disparity carries over).
		worst = std::max(worst, (o.corr[i].z_curr.head<2>() - t.head<2>()).cwiseAbs().maxCoeff());
		EXPECT_NEAR(o.corr[i].z_curr.x() - o.corr[i].z_curr.z(), t.x() - t.z(), 1e-4);
		const auto& lm = s.landmarks[o.landmark[i]];
		EXPECT_TRUE(o.corr[i].P_ref.isApprox(lm.P));
		// The keyframe's own measurement travels with the correspondence.
		EXPECT_EQ(o.corr[i].z_ref, Eigen::Vector3d(lm.uL, lm.v, lm.uR));
	}
	// The corners are up to 0.5 px from the truth; the refinement brings them
	// within 0.1 px (bilinear template against the cubic-interpolated image).
	EXPECT_LT(worst, 0.1);
}

TEST(VoKeyframeMatcher, TakenMeasurementsAreNeitherRefinedNorReturnedTheRestUnchanged)
{
	const auto s = makeScene(pose(0.05, -0.02, 0.3, 0.02), 6.0, 4);
	vo::KeyframeMatcher m;
	vo::TKeyframeMatchOutput all, masked;
	const auto in = inputFor(s, pose(0.08, -0.02, 0.3, 0.02));
	m.match(in, all);
	ASSERT_GE(all.corr.size(), 20u);
	// Every third landmark's true measurement is taken (a nearer keyframe has it).
	std::vector<uint8_t> taken(s.frame.meas.size(), 0);
	for (size_t j = 0; j < s.trueMeas.size(); j += 3) taken[static_cast<size_t>(s.trueMeas[j])] = 1;
	auto withMask = in;
	withMask.taken = &taken;
	m.match(withMask, masked);
	// Exactly the unmasked output without the taken measurements' correspondences.
	size_t k = 0;
	for (size_t i = 0; i < all.corr.size(); i++)
	{
		if (taken[static_cast<size_t>(all.measurement[i])]) continue;
		ASSERT_LT(k, masked.corr.size());
		EXPECT_EQ(masked.landmark[k], all.landmark[i]);
		EXPECT_EQ(masked.measurement[k], all.measurement[i]);
		EXPECT_EQ(masked.corr[k].z_curr, all.corr[i].z_curr);
		k++;
	}
	EXPECT_EQ(k, masked.corr.size());
	EXPECT_LT(masked.corr.size(), all.corr.size());
	EXPECT_EQ(masked.descriptor_matches, all.descriptor_matches);  // the search itself saw every measurement
	// A mask of the wrong size is refused.
	std::vector<uint8_t> wrong(s.frame.meas.size() + 1, 0);
	withMask.taken = &wrong;
	EXPECT_THROW(m.match(withMask, masked), std::invalid_argument);
}

TEST(VoKeyframeMatcher, CircleWidensWhenTheFirstTryFindsTooFew)
{
	const auto s = makeScene(pose(0.0, 0.0, 0.3, 0.0), 5.0, 2);
	vo::TKeyframeMatcherOptions opt;
	opt.search_radius_px = 4;
	opt.search_radius_lost_px = 30;
	vo::KeyframeMatcher m(opt);
	vo::TKeyframeMatchOutput o;
	// 0.15 m sideways at 5-7.5 m: 8-12 px off, outside the 4 px circle.
	m.match(inputFor(s, pose(0.15, 0.0, 0.3, 0.0)), o);
	EXPECT_TRUE(o.widened);
	EXPECT_EQ(correctMatches(s, o), static_cast<int>(s.landmarks.size()));
	// Told that it is lost, it starts wide.
	auto in = inputFor(s, pose(0.15, 0.0, 0.3, 0.0));
	in.wide = true;
	m.match(in, o);
	EXPECT_FALSE(o.widened);
	EXPECT_EQ(correctMatches(s, o), static_cast<int>(s.landmarks.size()));
}

TEST(VoKeyframeMatcher, GateFindsMatchesOutsideASmallCircleAndShrinksWithPoseCovariance)
{
	const auto s = makeScene(pose(0.0, 0.0, 0.3, 0.0), 5.0, 3);
	const Eigen::Isometry3d T_pred = pose(0.15, 0.0, 0.3, 0.0);	 // 8-12 px off along u
	// A small circle finds none of them.
	vo::TKeyframeMatcherOptions circle;
	circle.search_radius_px = circle.search_radius_lost_px = 5;
	vo::TKeyframeMatchOutput o;
	vo::KeyframeMatcher(circle).match(inputFor(s, T_pred), o);
	EXPECT_EQ(correctMatches(s, o), 0);

	vo::TKeyframeMatcherOptions gate;
	gate.region = vo::SearchRegion::Gate;
	const vo::KeyframeMatcher g(gate);
	// The prediction's translation uncertain by 0.1 m (1 sigma): 5-8 px at
	// these depths, the gate (sqrt(11.34) = 3.4 sigma) holds the true match.
	auto in = inputFor(s, T_pred);
	in.cov_T_curr_kf_pred = poseCov(0.1, 0.002);
	g.match(in, o);
	EXPECT_EQ(correctMatches(s, o), static_cast<int>(s.landmarks.size()));
	EXPECT_EQ(o.corr.size(), s.landmarks.size());
	// The gate is elongated: its extent along u exceeds the small circle.
	const auto pm = vo::KeyframeMatcher::predict(
		s.calib, T_pred, in.cov_T_curr_kf_pred, s.landmarks[0].P, s.landmarks[0].cov, gate.sigma_px);
	ASSERT_TRUE(pm.ok);
	const Eigen::Matrix3d G = g.gateMatrix(pm.S);
	EXPECT_GT(std::sqrt(gate.gate_chi2 * G(0, 0)), 5.0 * 2);

	// 100x smaller covariance: the gate shrinks (to its floor) and the true
	// matches, 8-12 px away, fall outside.
	in.cov_T_curr_kf_pred = poseCov(0.01, 0.0002);
	const auto pm2 = vo::KeyframeMatcher::predict(
		s.calib, T_pred, in.cov_T_curr_kf_pred, s.landmarks[0].P, s.landmarks[0].cov, gate.sigma_px);
	const Eigen::Matrix3d G2 = g.gateMatrix(pm2.S);
	EXPECT_LT(G2.determinant(), G.determinant());
	EXPECT_LT(G2(0, 0), G(0, 0));
	g.match(in, o);
	EXPECT_EQ(correctMatches(s, o), 0);
	// With the prediction right, the small gate finds them again.
	in.T_curr_kf_pred = s.T_curr_kf_true;
	g.match(in, o);
	EXPECT_EQ(correctMatches(s, o), static_cast<int>(s.landmarks.size()));
	// Even with no pose covariance at all: the 3 px floor holds the integer
	// corners (at most 0.7 px from the prediction).
	g.match(inputFor(s, s.T_curr_kf_true), o);
	EXPECT_EQ(correctMatches(s, o), static_cast<int>(s.landmarks.size()));
}

TEST(VoKeyframeMatcher, GateAxesAreClampedToFloorAndCeiling)
{
	vo::TKeyframeMatcherOptions opt;
	opt.region = vo::SearchRegion::Gate;
	opt.gate_min_px = 3;
	opt.gate_max_px = 50;
	const vo::KeyframeMatcher g(opt);
	Eigen::Matrix3d S = Eigen::Vector3d(0.01, 1e4, 4.0).asDiagonal();
	const Eigen::Matrix3d G = g.gateMatrix(S);
	EXPECT_NEAR(std::sqrt(opt.gate_chi2 * G(0, 0)), 3.0, 1e-9);
	EXPECT_NEAR(std::sqrt(opt.gate_chi2 * G(1, 1)), 50.0, 1e-9);
	EXPECT_NEAR(G(2, 2), 4.0, 1e-12);  // inside the bounds: unchanged
}

TEST(VoKeyframeMatcher, SeenFromASideTheLandmarksOwnUncertaintyIsSearchedNotCountedAsLost)
{
	// The current camera 2 m to the side of the keyframe (the other lane is
	// 3.5 m): a landmark triangulated over the 0.12 m baseline with 0.7 px of
	// noise per coordinate is uncertain along the epipolar line by about
	// 2 / 0.12 * 0.7 * sqrt(2) = 16 px (1 sigma) at any depth; its gate's long
	// axis (x sqrt(11.34)) is ~55 px plus the prediction's, past a 40 px ceiling.
	auto s = makeScene(pose(2.0, 0.0, 0.3, 0.0), 8.0, 11);
	for (auto& kf : s.landmarks)
	{
		// First-order covariance of the keyframe's triangulation.
		const double sz = 0.7;
		Eigen::Matrix3d J;
		for (int k = 0; k < 3; k++)
		{
			Eigen::Vector3d z(kf.uL, kf.v, kf.uR), zp = z, zm = z;
			zp[k] += 1e-3;
			zm[k] -= 1e-3;
			Eigen::Vector3d Pp, Pm;
			ASSERT_TRUE(s.calib.triangulate(zp.x(), zp.y(), zp.z(), Pp) && s.calib.triangulate(zm.x(), zm.y(), zm.z(), Pm));
			J.col(k) = (Pp - Pm) / 2e-3;
		}
		kf.cov = sz * sz * J * J.transpose();
	}
	const size_t n = s.landmarks.size();
	auto in = inputFor(s, s.T_curr_kf_true);
	in.cov_T_curr_kf_pred = poseCov(0.05, 0.005);
	vo::TKeyframeMatcherOptions opt;
	opt.region = vo::SearchRegion::Gate;
	opt.gate_max_px = 40;
	opt.gate_clamp = false;
	vo::TKeyframeMatchOutput o;
	// The whole gate under the ceiling (the VO's rule): every landmark overflows.
	vo::KeyframeMatcher(opt).match(in, o);
	EXPECT_EQ(o.gate.predicted, static_cast<int>(n));
	EXPECT_EQ(o.gate.overflow, static_cast<int>(n));
	EXPECT_EQ(correctMatches(s, o), 0);
	EXPECT_GT(o.gate.median_axis_px, 45.0);
	// The ceiling on the prediction's part: searched, all found, none lost.
	opt.gate_landmark_max_px = 150;
	vo::KeyframeMatcher(opt).match(in, o);
	EXPECT_EQ(o.gate.overflow, 0);
	EXPECT_EQ(o.gate.too_uncertain, 0);
	EXPECT_EQ(correctMatches(s, o), static_cast<int>(n));
	// ... but a landmark ceiling below the landmarks' gates leaves them out,
	// counted apart from the overflows.
	opt.gate_landmark_max_px = 41;
	vo::KeyframeMatcher(opt).match(in, o);
	EXPECT_EQ(o.gate.overflow, 0);
	EXPECT_EQ(o.gate.too_uncertain, static_cast<int>(n));
	EXPECT_EQ(correctMatches(s, o), 0);
	// A prediction too uncertain to search still overflows (the localiser is lost).
	opt.gate_landmark_max_px = 150;
	in.cov_T_curr_kf_pred = poseCov(1.0, 0.05);
	vo::KeyframeMatcher(opt).match(in, o);
	EXPECT_EQ(o.gate.overflow, static_cast<int>(n));
}

TEST(VoKeyframeMatcher, PredictedCovarianceMatchesMonteCarlo)
{
	// z = project(exp(xi) T P) + n with xi ~ N(0, C_T), P ~ N(P0, C_P), n ~ N(0, s^2 I).
	const auto c = test::stereoCalib();
	const Eigen::Isometry3d T = pose(0.2, -0.1, 0.4, 0.1);
	const Eigen::Vector3d P0(0.8, -0.4, 6.0);
	Matrix6d CT = Matrix6d::Zero();
	CT.diagonal() << 4e-4, 1e-4, 9e-4, 1e-6, 4e-6, 1e-6;
	CT(0, 4) = CT(4, 0) = 1e-6;
	const Eigen::Matrix3d CP = Eigen::Vector3d(1e-3, 1e-3, 2e-2).asDiagonal();
	const double sigma = 0.5;
	const auto pm = vo::KeyframeMatcher::predict(c, T, CT, P0, CP, sigma);
	ASSERT_TRUE(pm.ok);
	std::mt19937 rng(7);
	std::normal_distribution<double> N01;
	const Eigen::LLT<Matrix6d> LT(CT);
	const Eigen::LLT<Eigen::Matrix3d> LP(CP);
	const int n = 10000;
	std::vector<Eigen::Vector3d> z(n);
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	for (int i = 0; i < n; i++)
	{
		geometry::Vector6d e;
		for (int k = 0; k < 6; k++) e(k) = N01(rng);
		Eigen::Vector3d f(N01(rng), N01(rng), N01(rng)), g(N01(rng), N01(rng), N01(rng));
		const Eigen::Isometry3d Ti = geometry::retractLeft(LT.matrixL() * e, T);
		z[i] = c.project(Ti * (P0 + LP.matrixL() * f)) + sigma * g;
		mean += z[i];
	}
	mean /= n;
	Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
	for (const auto& zi : z) C += (zi - mean) * (zi - mean).transpose();
	C /= n - 1;
	// Relative Frobenius error; the sampling error of a 10^4-sample
	// covariance is about sqrt(2/n) = 1.4 % per entry.
	EXPECT_LT((C - pm.S).norm() / pm.S.norm(), 0.05) << "Monte Carlo\n" << C << "\nfirst order\n" << pm.S;
}

// ---- relative-pose estimator ------------------------------------------------------
namespace
{
/** Correspondences of landmarks seen from T_curr_ref with pixel noise; the
 * first `outliers` are moved by 20-60 px. */
std::vector<geometry::TStereoCorrespondence> makeCorr(
	const Eigen::Isometry3d& T_curr_ref, int n, int outliers, uint32_t seed)
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> ux(-4, 4), uy(-2, 2), uz(3, 25), uo(20, 60);
	std::normal_distribution<double> nz(0, 0.3);
	const auto c = test::stereoCalib();
	std::vector<geometry::TStereoCorrespondence> out;
	while (static_cast<int>(out.size()) < n)
	{
		geometry::TStereoCorrespondence k;
		const Eigen::Vector3d P(ux(rng), uy(rng), uz(rng));
		const Eigen::Vector3d zr = c.project(P) + Eigen::Vector3d(nz(rng), nz(rng), nz(rng));
		Eigen::Matrix3d J;
		if (!c.triangulate(zr.x(), zr.y(), zr.z(), k.P_ref, &J)) continue;
		k.cov_ref = c.triangulationCovariance(J, 0.3);
		k.z_ref = zr;
		k.calib_ref = c;
		const Eigen::Vector3d p = T_curr_ref * P;
		if (p.z() < 1) continue;
		k.z_curr = c.project(p) + Eigen::Vector3d(nz(rng), nz(rng), nz(rng));
		if (static_cast<int>(out.size()) < outliers) k.z_curr += Eigen::Vector3d(uo(rng), -uo(rng), 0);
		if (!c.triangulate(k.z_curr.x(), k.z_curr.y(), k.z_curr.z(), k.P_curr)) continue;
		out.push_back(k);
	}
	return out;
}
}  // namespace

TEST(VoRelativePoseEstimator, RecoversThePoseRejectsOutliersGivesCovariance)
{
	const Eigen::Isometry3d T = pose(0.1, 0.02, 0.6, 0.05);
	const auto corr = makeCorr(T, 120, 30, 11);
	for (const bool twoView : {true, false})
	{
		vo::TRelativePoseOptions opt;
		opt.two_view_ba = twoView;
		const vo::RelativePoseEstimator est(opt);
		vo::TRelativePoseInput in;
		in.corr = &corr;
		in.calib = test::stereoCalib();
		const Eigen::Isometry3d pred = pose(0.1, 0.0, 0.5, 0.05);
		in.T_curr_ref_pred = &pred;
		vo::TRelativePoseOutput out;
		est.estimate(in, out);
		ASSERT_TRUE(out.ok()) << toString(out.status);
		EXPECT_LT((out.T_curr_ref.translation() - T.translation()).norm(), 0.02) << "two_view " << twoView;
		EXPECT_LT(Eigen::AngleAxisd(out.T_curr_ref.linear() * T.linear().transpose()).angle(), 2e-3);
		for (int i = 0; i < 30; i++) EXPECT_FALSE(out.inlier[i]) << "outlier " << i;
		EXPECT_GE(out.inliers, 85u);
		EXPECT_EQ(out.inliers, static_cast<size_t>(std::count(out.inlier.begin(), out.inlier.end(), 1)));
		// A covariance: symmetric positive definite.
		EXPECT_LT((out.cov_T_ref_curr - out.cov_T_ref_curr.transpose()).norm(), 1e-12 * out.cov_T_ref_curr.norm());
		EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6d>(out.cov_T_ref_curr).eigenvalues().minCoeff(), 0.0);
	}
}

TEST(VoRelativePoseEstimator, WithoutThePriorTheLargestConsensusWins)
{
	// Two consistent sets: 40 matches of the true pose, 25 of a wrong one
	// (a repetitive structure matched one period off), 0.5 m apart. A
	// prediction at the wrong pose with a tight prior (0.08 m: the true set
	// pays 0.5 (0.5 / 0.08)^2 = 19.5 of its lead of 15) selects the wrong
	// set; solved without the prior (what a localiser's failure test needs),
	// the larger true set wins.
	const Eigen::Isometry3d T = pose(0.1, 0.02, 0.6, 0.05), T_wrong = pose(-0.4, 0.02, 0.6, 0.0);
	auto corr = makeCorr(T, 40, 0, 12);
	const auto w = makeCorr(T_wrong, 25, 0, 13);
	corr.insert(corr.end(), w.begin(), w.end());
	vo::TRelativePoseOptions opt;
	opt.ransac_prior_sigma_m = 0.08;
	const vo::RelativePoseEstimator est(opt);
	vo::TRelativePoseInput in;
	in.corr = &corr;
	in.calib = test::stereoCalib();
	in.T_curr_ref_pred = &T_wrong;
	vo::TRelativePoseOutput withPrior, without;
	est.estimate(in, withPrior);
	ASSERT_TRUE(withPrior.ok());
	EXPECT_LT((withPrior.T_curr_ref.translation() - T_wrong.translation()).norm(), 0.05);
	in.T_curr_ref_pred = nullptr;  // solved without the motion prior
	est.estimate(in, without);
	ASSERT_TRUE(without.ok());
	EXPECT_LT((without.T_curr_ref.translation() - T.translation()).norm(), 0.02);
	EXPECT_GE(without.inliers, 38u);
}

TEST(VoRelativePoseEstimator, TooFewCorrespondencesAreReported)
{
	const auto corr = makeCorr(pose(0, 0, 0.5, 0), 8, 0, 13);
	vo::TRelativePoseInput in;
	in.corr = &corr;
	in.calib = test::stereoCalib();
	vo::TRelativePoseOutput out;
	vo::RelativePoseEstimator().estimate(in, out);  // min_inliers 10 > 8
	EXPECT_EQ(out.status, vo::RelativePoseStatus::FewInliers);
}

// ---- keyframe policy and the VO's track/commit ----------------------------------------
TEST(VoKeyframePolicy, MotionPolicyFollowsItsThresholds)
{
	vo::TMotionKeyframePolicyOptions o;
	o.kf_translation = 1.0;
	o.kf_rotation_deg = 10;
	o.kf_min_tracked_fraction = 0.35;
	o.kf_min_inliers = 40;
	const vo::MotionKeyframePolicy p(o);
	vo::TKeyframeQuery q;
	q.inliers = 100;
	q.keyframe_landmarks = 200;
	q.T_kf_curr = pose(0, 0, 0.9, 0);
	EXPECT_FALSE(p.wantKeyframe(q));
	q.T_kf_curr = pose(0, 0, 1.1, 0);
	EXPECT_TRUE(p.wantKeyframe(q));	 // far
	q.T_kf_curr = pose(0, 0, 0.2, 11 * M_PI / 180);
	EXPECT_TRUE(p.wantKeyframe(q));	 // turned
	q.T_kf_curr = pose(0, 0, 0.2, 0);
	q.inliers = 60;
	EXPECT_TRUE(p.wantKeyframe(q));	 // 60 / 200 < 0.35: overlap lost
	q.keyframe_landmarks = 100;
	EXPECT_FALSE(p.wantKeyframe(q));
	q.inliers = 39;
	q.keyframe_landmarks = 50;
	EXPECT_TRUE(p.wantKeyframe(q));	 // too few inliers
}

namespace
{
struct TCorridorFrames
{
	geometry::TStereoCalib calib;
	std::vector<cv::Mat> monoL, monoR, invL, invR;
};
const TCorridorFrames& corridorFrames()
{
	static const TCorridorFrames f = [] {
		TCorridorFrames s;
		sim::SyntheticCorridor c;
		s.calib = c.calib();
		const filters::TChannel mono = filters::defaultChannel("mono"), inv = filters::defaultChannel("invariant");
		for (int k = 0; k < 12; k++)
		{
			cv::Mat l, r, a, b;
			c.render(sim::SyntheticCorridor::examplePose(k, 0.15), l, r, static_cast<uint32_t>(k));
			mono.convert(l, a);
			mono.convert(r, b);
			s.monoL.push_back(a.clone());
			s.monoR.push_back(b.clone());
			inv.convert(l, a);
			inv.convert(r, b);
			s.invL.push_back(a.clone());
			s.invR.push_back(b.clone());
		}
		return s;
	}();
	return f;
}
}  // namespace

TEST(VoStereoVO, TrackThenCommitEqualsProcessAndTheCallerCanForceOrForbidKeyframes)
{
	const auto& f = corridorFrames();
	vo::StereoVO a, b, forced, forbidden;
	for (auto* v : {&a, &b, &forced, &forbidden}) v->setMinLoggingLevel(mrpt::system::LVL_ERROR);
	size_t wanted = 0;
	for (size_t k = 0; k < f.monoL.size(); k++)
	{
		const auto ra = a.process(f.monoL[k], f.monoR[k], f.calib, 0.1 * k);
		const auto t = b.track(f.monoL[k], f.monoR[k], f.calib, 0.1 * k);
		EXPECT_THROW(b.track(f.monoL[k], f.monoR[k], f.calib, 0.1 * k), std::exception) << "track twice";
		const auto rb = b.commit();
		EXPECT_EQ(ra.keyframe, rb.keyframe) << k;
		EXPECT_EQ(ra.keyframe_wanted, t.keyframe_wanted) << k;
		EXPECT_TRUE(ra.T_world_curr.matrix() == rb.T_world_curr.matrix()) << k;
		wanted += ra.keyframe_wanted;

		forced.track(f.monoL[k], f.monoR[k], f.calib, 0.1 * k);
		const auto rf = forced.commit(vo::KeyframeDecision::Make);
		EXPECT_TRUE(vo::isTracked(rf.status)) << k;
		EXPECT_TRUE(rf.keyframe) << k;
		forbidden.track(f.monoL[k], f.monoR[k], f.calib, 0.1 * k);
		const auto rn = forbidden.commit(vo::KeyframeDecision::Skip);
		EXPECT_TRUE(vo::isTracked(rn.status)) << k;
		EXPECT_EQ(rn.keyframe, k == 0) << k;
	}
	EXPECT_EQ(a.keyframes().size(), 1 + wanted);
	EXPECT_GE(wanted, 1u);	// 1.65 m at 0.15 m per frame: the 1 m threshold is crossed
	EXPECT_LT(wanted, f.monoL.size() - 1);
	EXPECT_EQ(forced.keyframes().size(), f.monoL.size());
	EXPECT_EQ(forbidden.keyframes().size(), 1u);
	EXPECT_THROW(a.commit(), std::exception) << "commit without track";
}

TEST(VoStereoVO, TwoChannelsShareOneKeyframeSchedule)
{
	const auto& f = corridorFrames();
	vo::StereoVO mono, inv;
	mono.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	inv.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	// A tighter policy shared by both: a keyframe every ~0.4 m.
	vo::TMotionKeyframePolicyOptions po;
	po.kf_translation = 0.4;
	const auto policy = std::make_shared<vo::MotionKeyframePolicy>(po);
	mono.setKeyframePolicy(policy);
	inv.setKeyframePolicy(policy);
	for (size_t k = 0; k < f.monoL.size(); k++)
	{
		const auto a = mono.track(f.monoL[k], f.monoR[k], f.calib, 0.1 * k);
		const auto b = inv.track(f.invL[k], f.invR[k], f.calib, 0.1 * k);
		const auto d = a.keyframe_wanted || b.keyframe_wanted ? vo::KeyframeDecision::Make : vo::KeyframeDecision::Skip;
		const auto ra = mono.commit(d), rb = inv.commit(d);
		ASSERT_TRUE(vo::isTracked(ra.status) && vo::isTracked(rb.status)) << k;
		EXPECT_EQ(ra.keyframe, rb.keyframe) << k;
	}
	ASSERT_EQ(mono.keyframes().size(), inv.keyframes().size());
	EXPECT_GE(mono.keyframes().size(), 3u);
	for (size_t i = 0; i < mono.keyframes().size(); i++)
		EXPECT_EQ(mono.keyframes()[i].frame, inv.keyframes()[i].frame) << i;
}
