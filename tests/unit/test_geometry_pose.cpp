/* Tests of the pose geometry: Jacobians against numeric differentiation,
 * closed-form 3D-3D alignment, RANSAC with outliers, Gauss-Newton and its
 * covariance. */
#include "../support/TestSupport.h"

#include <shadyloc/geometry/PoseSolver.h>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <random>

using namespace shadyloc::geometry;

namespace
{
using shadyloc::test::stereoCalib;

Eigen::Isometry3d somePose()
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = (Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitX()))
					 .toRotationMatrix();
	T.translation() = Eigen::Vector3d(0.2, -0.05, 0.5);
	return T;
}

/** Landmarks in front of the reference camera, and their noisy measurements
 * from the current camera (T_curr_ref); `outliers` of them replaced by junk. */
std::vector<TStereoCorrespondence> makeProblem(
	const Eigen::Isometry3d& T_curr_ref, int n, int outliers, double noise_px, uint32_t seed)
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> ux(-4, 4), uy(-2, 2), uz(3, 25), uo(-60, 60);
	std::normal_distribution<double> nz(0, noise_px);
	const TStereoCalib c = stereoCalib();
	std::vector<TStereoCorrespondence> out;
	while (static_cast<int>(out.size()) < n)
	{
		TStereoCorrespondence k;
		k.P_ref = Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
		const Eigen::Vector3d p = T_curr_ref * k.P_ref;
		if (p.z() < 1) continue;
		k.z_curr = c.project(p) + Eigen::Vector3d(nz(rng), nz(rng), nz(rng));
		if (static_cast<int>(out.size()) < outliers) k.z_curr += Eigen::Vector3d(uo(rng), uo(rng), 0);
		if (!c.triangulate(k.z_curr.x(), k.z_curr.y(), k.z_curr.z(), k.P_curr)) continue;
		out.push_back(k);
	}
	return out;
}
double transErr(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B)
{
	return (A.translation() - B.translation()).norm();
}
double rotErrDeg(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B)
{
	return Eigen::AngleAxisd(A.linear().transpose() * B.linear()).angle() * 180 / M_PI;
}
}  // namespace

TEST(GeometryPose, ResidualJacobianMatchesNumeric)
{
	const TStereoCalib c = stereoCalib();
	const Eigen::Isometry3d T = somePose();
	const Eigen::Vector3d P(0.8, -0.3, 5.0), z(300, 180, 290);
	Eigen::Vector3d r;
	Matrix36d J;
	ASSERT_TRUE(stereoResidual(c, T, P, z, r, &J));
	const double h = 1e-6;
	for (int k = 0; k < 6; k++)
	{
		Vector6d d = Vector6d::Zero();
		d(k) = h;
		Eigen::Vector3d rp, rm;
		ASSERT_TRUE(stereoResidual(c, retractLeft(d, T), P, z, rp));
		ASSERT_TRUE(stereoResidual(c, retractLeft(-d, T), P, z, rm));
		const Eigen::Vector3d num = (rp - rm) / (2 * h);
		// Central differences on ~100 px/m quantities: 1e-4 relative is numeric noise.
		EXPECT_LT((num - J.col(k)).norm(), 1e-4 * std::max(1.0, num.norm())) << "column " << k;
	}
}

TEST(GeometryPose, CovarianceInversionMatchesSampling)
{
	// Cov(T^-1) from the adjoint, against the spread of sampled inverses.
	const Eigen::Isometry3d T = somePose();
	Matrix6d C = Matrix6d::Zero();
	C.diagonal() << 1e-4, 2e-4, 4e-4, 1e-5, 3e-5, 2e-5;
	const Matrix6d Cinv = invertCovariance(T, C);
	std::mt19937 rng(5);
	std::normal_distribution<double> n01;
	const Eigen::LLT<Matrix6d> L(C);
	Matrix6d S = Matrix6d::Zero();
	const int N = 20000;
	const Eigen::Isometry3d Ti = T.inverse();
	for (int i = 0; i < N; i++)
	{
		Vector6d w;
		for (int k = 0; k < 6; k++) w(k) = n01(rng);
		const Eigen::Isometry3d Ts = retractLeft(L.matrixL() * w, T).inverse();
		// xi with Ts = retract(xi, Ti): rotation part from R_s Ri^T, translation t_s - dR t_i.
		const Eigen::Matrix3d dR = Ts.linear() * Ti.linear().transpose();
		const Eigen::AngleAxisd aa(dR);
		Vector6d xi;
		xi.tail<3>() = aa.angle() * aa.axis();
		xi.head<3>() = Ts.translation() - dR * Ti.translation();
		S += xi * xi.transpose();
	}
	S /= N;
	// Sampling error of a variance estimate with N = 20000 is ~1 %; 5 % of the
	// largest entry bounds it with margin and still catches a wrong adjoint.
	EXPECT_LT((S - Cinv).cwiseAbs().maxCoeff(), 0.05 * Cinv.cwiseAbs().maxCoeff());
}

TEST(GeometryPose, RigidTransformIsExactAndRejectsCollinear)
{
	const Eigen::Isometry3d T = somePose();
	std::vector<Eigen::Vector3d> s = {{0, 0, 5}, {1, 0, 6}, {0, 1, 7}, {2, -1, 9}}, d;
	for (const auto& p : s) d.push_back(T * p);
	Eigen::Isometry3d E;
	ASSERT_TRUE(rigidTransform3D(s, d, E));
	EXPECT_LT(transErr(E, T), 1e-9);
	EXPECT_LT(rotErrDeg(E, T), 1e-6);
	std::vector<Eigen::Vector3d> line = {{0, 0, 1}, {0, 0, 2}, {0, 0, 3}};
	EXPECT_FALSE(rigidTransform3D(line, line, E));
}

TEST(GeometryPose, RansacAndSolverRecoverPoseDespiteOutliers)
{
	const Eigen::Isometry3d T = somePose();
	// 200 correspondences, 30 % outliers, 0.5 px noise.
	const auto c = makeProblem(T, 200, 60, 0.5, 11);
	TRansacOptions ro;
	const auto rs = ransacStereoPose(stereoCalib(), c, ro);
	ASSERT_TRUE(rs.ok);
	int falseIn = 0, trueIn = 0;
	for (int i = 0; i < 200; i++) (i < 60 ? falseIn : trueIn) += rs.inlier[i];
	// Outliers are shifted by up to 60 px; a few may land within 2 px by chance.
	EXPECT_LE(falseIn, 3);
	EXPECT_GE(trueIn, 130);	 // 2 px bound on 0.5 px noise (3-vector norm): ~99 % of 140
	TPoseSolverOptions so;
	so.use_landmark_covariance = false;	 // these landmarks are exact
	const auto sol = solveStereoPose(stereoCalib(), c, rs.inlier, rs.T_curr_ref, so);
	ASSERT_TRUE(sol.ok);
	// 140 points at 3-25 m with 0.5 px noise: the pose is good to a few mm / 0.05 deg.
	EXPECT_LT(transErr(sol.T_curr_ref, T), 0.01);
	EXPECT_LT(rotErrDeg(sol.T_curr_ref, T), 0.05);
	EXPECT_NEAR(sol.rms_px, 0.5, 0.1);
}

TEST(GeometryPose, CovarianceMatchesMonteCarloSpread)
{
	// Solve the same geometry under 200 noise draws: the spread of the
	// estimates must agree with the reported covariance.
	const Eigen::Isometry3d T = somePose();
	TPoseSolverOptions so;
	so.use_landmark_covariance = false;
	so.sigma_px = 0.5;
	so.huber_k = 100;  // plain least squares: the covariance formula assumes it
	Matrix6d S = Matrix6d::Zero(), Cmean = Matrix6d::Zero();
	const int N = 200;
	const Eigen::Isometry3d Ti = T.inverse();
	for (int i = 0; i < N; i++)
	{
		const auto c = makeProblem(T, 80, 0, 0.5, 100 + i);
		const auto sol = solveStereoPose(stereoCalib(), c, {}, T, so);
		ASSERT_TRUE(sol.ok);
		const Eigen::Isometry3d E = sol.T_curr_ref.inverse();  // the covariance is of T_ref_curr
		const Eigen::Matrix3d dR = E.linear() * Ti.linear().transpose();
		const Eigen::AngleAxisd aa(dR);
		Vector6d xi;
		xi.tail<3>() = aa.angle() * aa.axis();
		xi.head<3>() = E.translation() - dR * Ti.translation();
		S += xi * xi.transpose();
		Cmean += sol.cov_T_ref_curr;
	}
	S /= N;
	Cmean /= N;
	// Each problem has different landmarks, so compare the mean covariance.
	// With N = 200 a variance estimate has ~10 % standard error: accept the
	// ratio of diagonals within [0.6, 1.6].
	for (int k = 0; k < 6; k++)
	{
		const double ratio = S(k, k) / Cmean(k, k);
		EXPECT_GT(ratio, 0.6) << "axis " << k;
		EXPECT_LT(ratio, 1.6) << "axis " << k;
	}
}

namespace
{
/** Both views noisy, as in the VO: the reference landmark is triangulated
 * from a noisy reference measurement (covariance from the same noise), the
 * current measurement is noisy too. Depths in [zmin, zmax]; uR noisier by
 * disparity_noise_px in both views (a channel with poorer stereo). */
std::vector<TStereoCorrespondence> makeTwoViewProblem(
	const Eigen::Isometry3d& T_curr_ref, int n, double noise_px, double zmin, double zmax, uint32_t seed,
	double disparity_noise_px = 0)
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> ux(-0.45, 0.45), uy(-0.3, 0.3), uz(zmin, zmax);
	std::normal_distribution<double> nz(0, noise_px);
	const TStereoCalib c = stereoCalib();
	std::vector<TStereoCorrespondence> out;
	while (static_cast<int>(out.size()) < n)
	{
		const double Z = uz(rng);
		const Eigen::Vector3d P(ux(rng) * Z, uy(rng) * Z, Z);
		const Eigen::Vector3d p = T_curr_ref * P;
		if (p.z() < 1) continue;
		Eigen::Vector3d zr = c.project(P) + Eigen::Vector3d(nz(rng), nz(rng), nz(rng));
		TStereoCorrespondence k;
		k.z_curr = c.project(p) + Eigen::Vector3d(nz(rng), nz(rng), nz(rng));
		if (disparity_noise_px > 0)
		{
			std::normal_distribution<double> nd(0, disparity_noise_px);
			zr.z() += nd(rng);
			k.z_curr.z() += nd(rng);
			if (!(zr.x() - zr.z() > 0.3) || !(k.z_curr.x() - k.z_curr.z() > 0.3)) continue;
		}
		Eigen::Matrix3d J;
		if (!c.triangulate(zr.x(), zr.y(), zr.z(), k.P_ref, &J)) continue;
		if (!c.triangulate(k.z_curr.x(), k.z_curr.y(), k.z_curr.z(), k.P_curr)) continue;
		k.cov_ref = c.triangulationCovariance(J, noise_px);
		k.z_ref = zr;
		k.calib_ref = c;
		out.push_back(k);
	}
	return out;
}
}  // namespace

TEST(GeometryPose, TwoViewAdjustmentIsUnbiasedOnFarField)
{
	// Forward motion of 0.7 m among landmarks at 12-40 m (disparity 1.2-4 px),
	// 0.3 px noise in both views: the invariant channel's situation outdoors.
	// The fixed-landmark solve comes out short on average (measured -0.014 m,
	// 2 %: the shortening seen on the simulator); the two-view adjustment
	// must not, and must scatter less.
	Eigen::Isometry3d T_ref_curr = Eigen::Isometry3d::Identity();
	T_ref_curr.translation() = Eigen::Vector3d(0.02, 0.0, 0.7);
	const Eigen::Isometry3d T = T_ref_curr.inverse();
	TPoseSolverOptions so;
	so.sigma_px = 0.3;
	so.huber_k = 100;  // plain least squares: the covariance formula assumes it
	double e1 = 0, e2 = 0, bias1 = 0, bias2 = 0, var2 = 0;
	const int N = 100;
	for (int i = 0; i < N; i++)
	{
		const auto c = makeTwoViewProblem(T, 60, 0.3, 12, 40, 500 + i);
		const auto a = solveStereoPose(stereoCalib(), c, {}, T, so);
		const auto b = solveStereoPoseTwoView(stereoCalib(), c, {}, T, so);
		ASSERT_TRUE(a.ok && b.ok);
		const double za = a.T_curr_ref.inverse().translation().z(), zb = b.T_curr_ref.inverse().translation().z();
		e1 += (za - 0.7) * (za - 0.7);
		e2 += (zb - 0.7) * (zb - 0.7);
		bias1 += za - 0.7;
		bias2 += zb - 0.7;
		var2 += b.cov_T_ref_curr(2, 2);
		// Rotations stay exact rotations.
		const Eigen::Matrix3d R = b.T_curr_ref.linear();
		EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
	}
	const double rms1 = std::sqrt(e1 / N), rms2 = std::sqrt(e2 / N);
	std::printf("forward step: fixed landmarks rms %.4f m, mean %+.4f m | two-view rms %.4f m, mean %+.4f m, "
				"reported sigma %.4f m\n",
		rms1, bias1 / N, rms2, bias2 / N, std::sqrt(var2 / N));
	// Standard error of the mean over 100 draws: ~0.016 / 10 = 0.0016 m; 3x that.
	EXPECT_LT(std::abs(bias2 / N), 0.005);
	EXPECT_LT(rms2, rms1);
	// Reported covariance against the spread (100 draws: ~14 % standard error
	// of an rms; accept a ratio within [0.7, 1.4]).
	const double ratio = rms2 / std::sqrt(var2 / N);
	EXPECT_GT(ratio, 0.7);
	EXPECT_LT(ratio, 1.4);
}

TEST(GeometryPose, DisparityNoiseWeighsTheRightImageLess)
{
	// The invariant channel places corners about as well as the monochrome
	// one but measures their disparity worse (docs/localisation.md, "Where
	// the invariant solves' error comes from"). With uR 1 px noisier than
	// uL and v (0.2 px) in both views, a solve that knows it must scatter
	// less than one that weighs uR like uL (measured 9 % less: the same
	// draws for both, so 3 % is a margin), and its covariance must match its
	// spread where the other's claims a third of it (measured).
	Eigen::Isometry3d T_ref_curr = Eigen::Isometry3d::Identity();
	T_ref_curr.translation() = Eigen::Vector3d(0.1, 0.0, 0.8);
	const Eigen::Isometry3d T = T_ref_curr.inverse();
	TPoseSolverOptions flat, model;
	flat.sigma_px = model.sigma_px = 0.2;
	flat.huber_k = model.huber_k = 100;  // plain least squares: the covariance formula assumes it
	model.sigma_disparity_px = 1.0;
	double eFlat = 0, eModel = 0, varFlat = 0, varModel = 0;
	const int N = 100;
	for (int i = 0; i < N; i++)
	{
		const auto c = makeTwoViewProblem(T, 60, 0.2, 4, 25, 900 + i, 1.0);
		const auto a = solveStereoPoseTwoView(stereoCalib(), c, {}, T, flat);
		const auto b = solveStereoPoseTwoView(stereoCalib(), c, {}, T, model);
		ASSERT_TRUE(a.ok && b.ok);
		eFlat += (a.T_curr_ref.inverse().translation() - T_ref_curr.translation()).squaredNorm();
		eModel += (b.T_curr_ref.inverse().translation() - T_ref_curr.translation()).squaredNorm();
		varFlat += a.cov_T_ref_curr.topLeftCorner<3, 3>().trace();
		varModel += b.cov_T_ref_curr.topLeftCorner<3, 3>().trace();
	}
	const double rmsFlat = std::sqrt(eFlat / N), rmsModel = std::sqrt(eModel / N);
	std::printf("translation rms: uR weighed as uL %.4f m (reported %.4f m), with the disparity noise %.4f m "
				"(reported %.4f m)\n",
				rmsFlat, std::sqrt(varFlat / N), rmsModel, std::sqrt(varModel / N));
	EXPECT_LT(rmsModel, 0.97 * rmsFlat);
	EXPECT_GT(rmsFlat / std::sqrt(varFlat / N), 2.0);
	// 100 draws: ~14 % standard error of an rms; accept a ratio within [0.7, 1.4].
	const double ratio = rmsModel / std::sqrt(varModel / N);
	EXPECT_GT(ratio, 0.7);
	EXPECT_LT(ratio, 1.4);
}

TEST(GeometryPose, RetractionKeepsRotationsExact)
{
	// A start whose rotation is off SO(3) by rounding-like error (a motion
	// prediction composed of earlier solutions) must come back exact, or the
	// error grows when the result is fed back as the next prediction.
	Eigen::Isometry3d T = somePose();
	T.linear() *= 1.0 + 1e-6;
	T.linear()(0, 1) += 1e-6;
	Vector6d xi;
	xi << 0.01, -0.02, 0.03, 0.001, 0.002, -0.003;
	const Eigen::Matrix3d R = retractLeft(xi, T).linear();
	EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
	EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

TEST(GeometryPose, PriorPrefersTheConsensusNearThePrediction)
{
	// 12 true matches for a 0.9 m forward step, 16 that agree on a 0.25 m step
	// (a repetitive structure matched one period off), 20 random outliers.
	// Inlier counting picks the larger, wrong set; with the prediction as the
	// first hypothesis and a prior of 0.15 m per frame the true step wins
	// (the wrong one is 0.65 m = 4.3 sigma from the prediction: a penalty of
	// 9.4 inliers against its lead of 4).
	auto forward = [](double z) {
		Eigen::Isometry3d T_ref_curr = Eigen::Isometry3d::Identity();
		T_ref_curr.translation() = Eigen::Vector3d(0, 0, z);
		return T_ref_curr.inverse();
	};
	const Eigen::Isometry3d T_true = forward(0.9), T_wrong = forward(0.25);
	auto c = makeTwoViewProblem(T_true, 12, 0.3, 4, 30, 7);
	const auto w = makeTwoViewProblem(T_wrong, 16, 0.3, 4, 30, 8);
	c.insert(c.end(), w.begin(), w.end());
	std::mt19937 rng(9);
	std::uniform_real_distribution<double> uu(20, 490), uv(20, 360), ud(2, 40);
	for (int i = 0; i < 20; i++)
	{
		TStereoCorrespondence k = c[i % 12];
		k.z_curr = Eigen::Vector3d(uu(rng), uv(rng), 0);
		k.z_curr.z() = k.z_curr.x() - ud(rng);
		ASSERT_TRUE(stereoCalib().triangulate(k.z_curr.x(), k.z_curr.y(), k.z_curr.z(), k.P_curr));
		c.push_back(k);
	}
	TRansacOptions ro;
	ro.inlier_threshold_px = 4;
	ro.hypotheses.push_back(forward(0.88));	 // the constant-velocity prediction, 2 cm off
	const auto plain = ransacStereoPose(stereoCalib(), c, ro);
	ro.prior_sigma_m = 0.15;
	const auto withPrior = ransacStereoPose(stereoCalib(), c, ro);
	ASSERT_TRUE(plain.ok && withPrior.ok);
	EXPECT_LT(transErr(plain.T_curr_ref, T_wrong), 0.1);  // inlier counting alone: the wrong set
	EXPECT_LT(transErr(withPrior.T_curr_ref, T_true), 0.1);
	int trueIn = 0;
	for (int i = 0; i < 12; i++) trueIn += withPrior.inlier[i];
	EXPECT_GE(trueIn, 10);
}

TEST(GeometryPose, TwoViewAdjustmentUsesTheReferenceCalibration)
{
	// The reference frame (a map's keyframe) was taken with another camera
	// than the live one: focal length 560 px, principal point moved, baseline
	// 0.24 m. Each landmark's reference measurement is projected with that
	// calibration; projecting it with the live one (the former behaviour)
	// would put every landmark somewhere else.
	TStereoCalib ref = stereoCalib();
	ref.fx = ref.fy = 560;
	ref.cx = 300;
	ref.cxR = 302;
	ref.cy = 200;
	ref.baseline = 0.24;
	const TStereoCalib live = stereoCalib();
	const Eigen::Isometry3d T = somePose();
	std::mt19937 rng(3);
	std::uniform_real_distribution<double> ux(-3, 3), uy(-1.5, 1.5), uz(4, 20);
	std::vector<TStereoCorrespondence> c;
	while (c.size() < 50)
	{
		const Eigen::Vector3d P(ux(rng), uy(rng), uz(rng));
		const Eigen::Vector3d p = T * P;
		if (p.z() < 1) continue;
		TStereoCorrespondence k;
		k.z_ref = ref.project(P);
		k.calib_ref = ref;
		ASSERT_TRUE(ref.triangulate(k.z_ref.x(), k.z_ref.y(), k.z_ref.z(), k.P_ref));
		k.z_curr = live.project(p);
		ASSERT_TRUE(live.triangulate(k.z_curr.x(), k.z_curr.y(), k.z_curr.z(), k.P_curr));
		c.push_back(k);
	}
	TPoseSolverOptions so;
	so.sigma_px = 0.5;
	Eigen::Isometry3d T0 = T;
	T0.translation() += Eigen::Vector3d(0.05, -0.03, 0.1);
	const auto sol = solveStereoPoseTwoView(live, c, {}, T0, so);
	ASSERT_TRUE(sol.ok);
	// Noise-free measurements: the exact pose, up to the solver's convergence.
	EXPECT_LT(transErr(sol.T_curr_ref, T), 1e-6);
	EXPECT_LT(sol.rms_px, 1e-6);
	// With the live calibration as the reference's the problem is inconsistent.
	auto wrong = c;
	for (auto& k : wrong) k.calib_ref = live;
	const auto bad = solveStereoPoseTwoView(live, wrong, {}, T0, so);
	EXPECT_TRUE(!bad.ok || bad.rms_px > 1.0 || transErr(bad.T_curr_ref, T) > 0.05);

	// A used correspondence without a reference observation is an error.
	auto missing = c;
	missing[7].z_ref.setConstant(std::numeric_limits<double>::quiet_NaN());
	EXPECT_THROW(solveStereoPoseTwoView(live, missing, {}, T0, so), std::invalid_argument);
	std::vector<uint8_t> use(c.size(), 1);
	use[7] = 0;	 // ... unless it is not used
	EXPECT_TRUE(solveStereoPoseTwoView(live, missing, use, T0, so).ok);
}

TEST(GeometryPose, CountedSolveEqualsTheSolveOverTheRepeatedList)
{
	// A bootstrap resample as counts must solve as the list it stands for,
	// with or without the shared first linearisation; a Huber-weighted
	// outlier keeps the robust weights in play.
	const Eigen::Isometry3d T = somePose();
	const auto c = makeProblem(T, 40, 2, 0.5, 5);
	TPoseSolverOptions so;
	so.max_iterations = 5;
	const auto fit = solveStereoPose(stereoCalib(), c, {}, T, so);
	ASSERT_TRUE(fit.ok);
	std::mt19937 rng(3);
	std::uniform_int_distribution<size_t> pick(0, c.size() - 1);
	const auto atFit = normalTermsAt(stereoCalib(), c, fit.T_curr_ref, so);
	for (int b = 0; b < 5; b++)
	{
		std::vector<int> count(c.size(), 0);
		std::vector<TStereoCorrespondence> repeated;
		for (size_t k = 0; k < c.size(); k++)
		{
			const size_t i = pick(rng);
			count[i]++;
			repeated.push_back(c[i]);
		}
		const auto ref = solveStereoPose(stereoCalib(), repeated, {}, fit.T_curr_ref, so);
		for (const auto* terms : {static_cast<const std::vector<TNormalTerms>*>(nullptr), &atFit})
		{
			const auto got = solveStereoPoseCounted(stereoCalib(), c, count, fit.T_curr_ref, so, terms);
			ASSERT_EQ(got.ok, ref.ok);
			EXPECT_LT(transErr(got.T_curr_ref, ref.T_curr_ref), 1e-9);
			EXPECT_LT(rotErrDeg(got.T_curr_ref, ref.T_curr_ref), 1e-7);
			EXPECT_LT((got.cov_T_ref_curr - ref.cov_T_ref_curr).norm(), 1e-9 * ref.cov_T_ref_curr.norm());
			EXPECT_EQ(got.iterations, ref.iterations);
		}
		// A resample that differs from the list does not solve as it.
		std::vector<int> other = count;
		std::fill(other.begin(), other.begin() + 10, 0);
		const auto off = solveStereoPoseCounted(stereoCalib(), c, other, fit.T_curr_ref, so, &atFit);
		ASSERT_TRUE(off.ok);
		EXPECT_GT(transErr(off.T_curr_ref, ref.T_curr_ref), 1e-6);
	}
	EXPECT_THROW(solveStereoPoseCounted(stereoCalib(), c, std::vector<int>(3, 1), T, so), std::invalid_argument);
}

TEST(GeometryPose, ChordSolveReachesTheRelinearisedResamplesPose)
{
	// The chord method keeps the solve's Jacobians: a resample's pose must be
	// the re-linearised solver's to a small share of how far the resample
	// moves it from the solve, yet not simply stay at the solve. Outliers and
	// far landmarks keep the Huber weights and the nonlinearity in play.
	const Eigen::Isometry3d T = somePose();
	const auto c = makeProblem(T, 40, 3, 0.5, 9);
	TPoseSolverOptions so;
	so.max_iterations = 30;
	const auto fit = solveStereoPose(stereoCalib(), c, {}, T, so);
	ASSERT_TRUE(fit.ok);
	so.covariance = false;
	const auto frozen = frozenTermsAt(stereoCalib(), c, fit.T_curr_ref, so);
	std::mt19937 rng(5);
	std::uniform_int_distribution<size_t> pick(0, c.size() - 1);
	for (int b = 0; b < 10; b++)
	{
		std::vector<int> count(c.size(), 0);
		for (size_t k = 0; k < c.size(); k++) count[pick(rng)]++;
		const auto exact = solveStereoPoseCounted(stereoCalib(), c, count, fit.T_curr_ref, so);
		const auto chord = solveStereoPoseCountedChord(stereoCalib(), c, count, fit.T_curr_ref, so, frozen);
		ASSERT_TRUE(exact.ok && chord.ok);
		const double moved = transErr(exact.T_curr_ref, fit.T_curr_ref);
		ASSERT_GT(moved, 1e-4);  // a resample moves the pose by about its sigma (mm to cm here)
		EXPECT_LT(transErr(chord.T_curr_ref, exact.T_curr_ref), 0.02 * moved);
		EXPECT_LT(rotErrDeg(chord.T_curr_ref, exact.T_curr_ref), 0.02 * rotErrDeg(exact.T_curr_ref, fit.T_curr_ref) + 1e-6);
	}
	// The frozen terms at the solve give its first step exactly: a resample
	// of every correspondence once stays at the solve.
	const auto same =
		solveStereoPoseCountedChord(stereoCalib(), c, std::vector<int>(c.size(), 1), fit.T_curr_ref, so, frozen);
	ASSERT_TRUE(same.ok);
	EXPECT_LT(transErr(same.T_curr_ref, fit.T_curr_ref), 1e-7);
	EXPECT_THROW(
		solveStereoPoseCountedChord(stereoCalib(), c, std::vector<int>(3, 1), T, so, frozen), std::invalid_argument);
	TPoseSolverOptions withCov = so;
	withCov.covariance = true;
	EXPECT_THROW(
		solveStereoPoseCountedChord(stereoCalib(), c, std::vector<int>(c.size(), 1), T, withCov, frozen),
		std::invalid_argument);
}

TEST(GeometryPose, PoseOnlySolveGivesTheSamePoseToTheBit)
{
	// RANSAC's local optimisation and the bootstrap's resamples use only the
	// pose: without the covariance a solve must stop at the same pose, to the
	// bit, whether it converges or runs out of iterations, in both solvers.
	const Eigen::Isometry3d T = somePose();
	Eigen::Isometry3d start = T;
	start.translation() += Eigen::Vector3d(0.05, -0.02, 0.1);
	for (const int iterations : {1, 2, 15})
		for (const bool twoView : {false, true})
		{
			SCOPED_TRACE(std::to_string(iterations) + (twoView ? " iterations, two-view" : " iterations, one-view"));
			const auto c = twoView ? makeTwoViewProblem(T, 60, 0.5, 4, 30, 21) : makeProblem(T, 60, 6, 0.5, 21);
			TPoseSolverOptions full;
			full.max_iterations = iterations;
			TPoseSolverOptions poseOnly = full;
			poseOnly.covariance = false;
			const auto solve = twoView ? solveStereoPoseTwoView : solveStereoPose;
			const auto a = solve(stereoCalib(), c, {}, start, full);
			const auto b = solve(stereoCalib(), c, {}, start, poseOnly);
			ASSERT_TRUE(a.ok);
			ASSERT_TRUE(b.ok);
			EXPECT_EQ(b.iterations, a.iterations);
			EXPECT_TRUE(b.T_curr_ref.matrix() == a.T_curr_ref.matrix()) << b.T_curr_ref.matrix() - a.T_curr_ref.matrix();
			// The pose-only solve says nothing about its covariance.
			EXPECT_TRUE(b.cov_T_ref_curr.isIdentity(0));
			if (iterations == 15)
			{
				EXPECT_LT(transErr(b.T_curr_ref, T), 0.05);
			}
		}
}
