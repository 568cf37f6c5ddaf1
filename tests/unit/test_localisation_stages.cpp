/* ShadyLoc tests: the localisation stages without images — the accept
 * stage (FixAcceptance.h), the track and its policy (Track.h), the fix
 * covariance. Each of the bugs the localisation issue named has a case
 * here: drift that grew with the square root of the distance, a rejected
 * solve kept as the motion test's reference, an unconfirmed solve that
 * validated the next frame against itself, the bootstrap covariance
 * inflated twice. The joint localiser's solve of two channels' searches. */
#include <shadyloc/core/Units.h>
#include <shadyloc/localisation/FixAcceptance.h>
#include <shadyloc/localisation/JointLocaliser.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/localisation/StereoLocaliser.h>
#include <shadyloc/localisation/Track.h>

#include "test_map_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace
{
using namespace shadyloc;
using namespace shadyloc::localisation;
using geometry::Matrix6d;
using core::kDeg;

Matrix6d diag(double sm, double sdeg)
{
	Matrix6d c = Matrix6d::Zero();
	c.diagonal() << sm * sm, sm * sm, sm * sm, std::pow(sdeg * kDeg, 2), std::pow(sdeg * kDeg, 2), std::pow(sdeg * kDeg, 2);
	return c;
}

Eigen::Isometry3d ahead(double z)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.translation() = Eigen::Vector3d(0, 0, z);
	return T;
}

TKeyframePose poseAt(double z, double sm, uint32_t kf = 0)
{
	TKeyframePose p;
	p.valid = true;
	p.kf = kf;
	p.T_kf_live = ahead(z);
	p.cov = diag(sm, sm * 10);
	return p;
}

TMotion step(double dz, double sm = 0.005, double sdeg = 0.05)
{
	TMotion m;
	m.valid = true;
	m.T_prev_curr = ahead(dz);
	m.cov = diag(sm, sdeg);
	return m;
}

// One keyframe: every link is the identity.
geometry::TPoseWithCov identityLink(uint32_t, uint32_t) { return {}; }

// The system's test of a verified place against a prediction.
PlaceTest judged(const TKeyframePose& place)
{
	return [place](const TKeyframePose& pred) { return placeAgrees(place, pred, identityLink, 16.81); };
}

TSolve solveAt(size_t frame, double z, double sm = 0.02)
{
	TSolve s;
	s.frame = frame;
	s.pose = poseAt(z, sm);
	return s;
}
}  // namespace

// sigma of the drift is k times the distance since the last fix, whatever the
// step: before, each step added (k s)^2, so sigma was k sqrt(s D) (24 m at
// 0.8 m steps: 0.09 m instead of 0.48 m) and depended on the frame rate.
TEST(LocalisationStages, WholeMapSearchSweepsTheMapInBoundedSlices)
{
	// 10 keyframes, 4 a frame: 0-3, 4-7, then 8, 9, 0, 1 (ascending), ...
	MapSweep sweep(10, 4);
	std::vector<int> seen(10, 0);
	for (int round = 0; round < 5; round++)
	{
		const auto s = sweep.next();
		ASSERT_EQ(s.size(), 4u);
		EXPECT_TRUE(std::is_sorted(s.begin(), s.end()));
		for (const auto k : s) seen[k]++;
	}
	EXPECT_EQ(seen, std::vector<int>(10, 2));  // 20 looks: every keyframe twice
	sweep.restart();
	EXPECT_EQ(sweep.next(), (std::vector<uint32_t>{0, 1, 2, 3}));
	// No budget, or one beyond the map: the whole map every time.
	for (const int budget : {0, 10, 50})
	{
		MapSweep whole(10, budget);
		for (int round = 0; round < 3; round++) EXPECT_EQ(whole.next().size(), 10u) << budget;
	}
	EXPECT_TRUE(MapSweep(0, 4).next().empty());
}

TEST(LocalisationStages, DriftGrowsInProportionToDistanceWhateverTheStep)
{
	for (const double s : {0.1, 0.8, 3.0})
	{
		Matrix6d sum = Matrix6d::Zero();
		double d = 0;
		while (d < 24.0 - 1e-9)
		{
			sum += driftCovariance(d, s, 0.02, 0.2);
			d += s;
		}
		EXPECT_NEAR(std::sqrt(sum(0, 0)), 0.02 * d, 1e-9) << "step " << s;
		EXPECT_NEAR(std::sqrt(sum(5, 5)) / kDeg, 0.2 * d, 1e-9) << "step " << s;
	}
	// Through the track: 30 steps of 0.8 m with (almost) exact VO; along the
	// direction of travel (z) heading errors add nothing.
	TTrackOptions o;
	Track t(o);
	t.fix(poseAt(0, 1e-4));
	TKeyframePose p;
	for (int i = 0; i < 30; i++)
	{
		p = t.predict(step(0.8, 1e-6, 0));
		t.noFix({});
	}
	EXPECT_NEAR(std::sqrt(p.cov(2, 2)), 0.02 * 24.0, 0.005);
}

// A solve rejected as inconsistent is never the motion test's reference:
// before, the next (right) solve was tested against the rejected one and
// failed too.
TEST(LocalisationStages, RejectedSolveIsNeverAReference)
{
	FixAcceptance acc({22.46, 22.46, 2});
	const TMotion m = step(0.5);
	auto predAt = [](double z) { return poseAt(z, 0.05); };
	EXPECT_EQ(acc.judge(solveAt(1, 0.5), predAt(0.5), m, true, true, identityLink).verdict, AcceptanceVerdict::Fix);
	// Frame 2: 2 m off the prediction (a wrong keyframe's solve).
	const auto bad = acc.judge(solveAt(2, 3.0), predAt(1.0), m, true, true, identityLink);
	EXPECT_EQ(bad.verdict, AcceptanceVerdict::PredictionInconsistent);
	// Frame 3: right again. No reference from frame 2: the motion test does not run.
	const auto good = acc.judge(solveAt(3, 1.5), predAt(1.5), m, true, true, identityLink);
	EXPECT_EQ(good.verdict, AcceptanceVerdict::Fix);
	EXPECT_EQ(good.motion_d2, -1.0);
	// Frame 4 is tested against frame 3.
	const auto next = acc.judge(solveAt(4, 2.0), predAt(2.0), m, true, true, identityLink);
	EXPECT_GE(next.motion_d2, 0.0);
	EXPECT_EQ(next.verdict, AcceptanceVerdict::Fix);
}

// An uncertain solve must agree more closely with the prediction: the near
// misses the 99 % gate let through were solves 3-4 sigma from a good
// prediction with sigma 0.09-0.14 m (docs/localisation.md, "Uncertain
// solves"). A certain solve as far off in sigmas still passes.
TEST(LocalisationStages, AnUncertainSolveMustAgreeMoreClosely)
{
	const TMotion m = step(0.5);
	TAcceptanceOptions strict;
	strict.uncertain_sigma_m = 0.09;
	strict.uncertain_prediction_chi2 = 10;
	const auto pred = poseAt(1.0, 0.03);
	// 0.45 m ahead with sigma 0.12: d2 = 0.45^2 / (0.03^2 + 0.12^2) = 13.2.
	const TSolve uncertain = solveAt(1, 1.45, 0.12);
	// 0.2 m ahead with sigma 0.05: d2 = 0.2^2 / (0.03^2 + 0.05^2) = 11.8.
	const TSolve certain = solveAt(1, 1.2, 0.05);
	for (const TSolve& s : {uncertain, certain})
	{
		FixAcceptance usual({16.81, 22.46, 2});
		const auto a = usual.judge(s, pred, m, true, true, identityLink);
		EXPECT_GT(a.prediction_d2, 10.0);
		EXPECT_EQ(a.verdict, AcceptanceVerdict::Fix) << "without the rule, d2 " << a.prediction_d2;
	}
	FixAcceptance accU(strict), accC(strict);
	EXPECT_EQ(accU.judge(uncertain, pred, m, true, true, identityLink).verdict, AcceptanceVerdict::PredictionInconsistent);
	EXPECT_EQ(accC.judge(certain, pred, m, true, true, identityLink).verdict, AcceptanceVerdict::Fix);
	// The stricter gate never loosens the usual one.
	strict.uncertain_prediction_chi2 = 30;
	FixAcceptance loose(strict);
	EXPECT_EQ(
		loose.judge(solveAt(1, 1.7, 0.12), pred, m, true, true, identityLink).verdict,
		AcceptanceVerdict::PredictionInconsistent);
}

// K consistent frames for a new place; while the track is confirmed a
// consistent solve is a fix at once (the monochrome localiser no longer
// waits after a failure while the system knows where it is).
TEST(LocalisationStages, ConfirmationIsOnlyForANewPlace)
{
	const TMotion m = step(0.5);
	FixAcceptance fresh({22.46, 22.46, 2});
	std::vector<AcceptanceVerdict> v;
	for (size_t f = 1; f <= 3; f++)
		v.push_back(fresh.judge(solveAt(f, 0.5 * f), poseAt(0.5 * f, 0.05), m, false, true, identityLink).verdict);
	EXPECT_EQ(v[0], AcceptanceVerdict::Unconfirmed);  // no motion test yet
	EXPECT_EQ(v[1], AcceptanceVerdict::Unconfirmed);  // 1 of K
	EXPECT_EQ(v[2], AcceptanceVerdict::Fix);  // K = 2

	FixAcceptance tracked({22.46, 22.46, 2});
	EXPECT_EQ(tracked.judge(solveAt(1, 0.5), poseAt(0.5, 0.05), m, true, true, identityLink).verdict, AcceptanceVerdict::Fix);

	// A verified place counts as the first consistent frame: the next
	// consistent solve confirms it.
	FixAcceptance placed({22.46, 22.46, 2});
	placed.startFrom(7, poseAt(0.0, 0.05));
	const auto a = placed.judge(solveAt(8, 0.5), poseAt(0.5, 0.1), m, false, true, identityLink);
	EXPECT_GE(a.motion_d2, 0.0);
	EXPECT_EQ(a.verdict, AcceptanceVerdict::Fix);
	// ... and one that moved against VO is rejected.
	FixAcceptance placed2({22.46, 22.46, 2});
	placed2.startFrom(7, poseAt(0.0, 0.02));
	EXPECT_EQ(placed2.judge(solveAt(8, 1.5), poseAt(1.5, 1.0), m, false, true, identityLink).verdict,
			  AcceptanceVerdict::MotionInconsistent);
}

// An unconfirmed solve narrows the next search but is never what a solve is
// validated against: before, it became the estimate, so a wrong place
// confirmed itself through its own prediction.
TEST(LocalisationStages, UnconfirmedSeedNarrowsTheSearchButNeverValidates)
{
	TTrackOptions o;
	Track t(o);
	t.adoptPlace(poseAt(0, 0.3));  // a wide place
	t.predict(step(0.5));
	t.noFix({poseAt(5.0, 0.01)});  // a tight but wrong solve
	const TKeyframePose pred = t.predict(step(0.5));
	EXPECT_NEAR(pred.T_kf_live.translation().z(), 1.0, 1e-9);  // the track: place + VO
	ASSERT_TRUE(t.searchSeed().valid);
	EXPECT_NEAR(t.searchSeed().T_kf_live.translation().z(), 5.5, 1e-9);
	EXPECT_FALSE(t.confirmed());
}

// place_seeds_search: a verified place that is no fix narrows the next
// search with its own covariance; the track it is tested against keeps
// global_sigma added (with the added sigma alone the next frame's gates were
// 45-60 px wide and the monochrome search failed where the place's own 10 px
// found it again). A localiser option: on for monochrome only
// (docs/localisation.md, "Finding places sooner under hard light").
TEST(LocalisationStages, VerifiedPlaceNarrowsTheNextSearchButNeverValidates)
{
	TTrackOptions o;
	Track t(o);
	t.adoptPlace(poseAt(2.0, 0.01), /*seedsSearch=*/true);
	const TKeyframePose pred = t.predict(step(0.5));
	EXPECT_GE(geometry::translationSigma(pred.cov), o.global_sigma_m);	// tested against: the place made wide
	ASSERT_TRUE(t.searchSeed().valid);
	EXPECT_NEAR(t.searchSeed().T_kf_live.translation().z(), 2.5, 1e-9);
	EXPECT_LT(geometry::translationSigma(t.searchSeed().cov), 0.05);  // searched in: its own covariance and one step
	EXPECT_FALSE(t.confirmed());

	Track u(o);
	u.adoptPlace(poseAt(2.0, 0.01), /*seedsSearch=*/false);
	u.predict(step(0.5));
	EXPECT_FALSE(u.searchSeed().valid);

	// Through placeFound, as the system calls it: a new hypothesis seeds
	// only when its localiser's places may.
	const PlaceTest never = [](const TKeyframePose&) { return false; };
	Track w(o);
	EXPECT_EQ(w.placeFound(poseAt(2.0, 0.01), never, true, 3, /*seedsSearch=*/true), PlaceOutcome::Hypothesis);
	w.predict(step(0.5));
	EXPECT_TRUE(w.searchSeed().valid);
	Track x(o);
	EXPECT_EQ(x.placeFound(poseAt(2.0, 0.01), never, true, 3, /*seedsSearch=*/false), PlaceOutcome::Hypothesis);
	x.predict(step(0.5));
	EXPECT_FALSE(x.searchSeed().valid);
}

// The track is a confirmed place after a fix until its uncertainty outgrows
// the bound; the place is searched for around dead reckoning after
// relocalise_after_frames, everywhere after global_search_after_frames.
TEST(LocalisationStages, TrackConfirmationAndRelocalisation)
{
	TTrackOptions o;
	o.relocalise_after_frames = 2;
	o.global_search_after_frames = 10;
	o.confirmed_max_sigma_m = 0.5;
	o.drift_deg_per_m = 0;	// heading drift would add lateral error: here the distance alone
	Track t(o);
	EXPECT_EQ(t.searchNeeded(false), SearchScope::Whole);  // no place yet
	t.fix(poseAt(0, 0.01));
	t.predict(step(0.8, 1e-6, 0));
	EXPECT_TRUE(t.confirmed());
	t.noFix({});
	EXPECT_EQ(t.searchNeeded(false), SearchScope::None);
	EXPECT_EQ(t.searchNeeded(true), SearchScope::Window);  // every localiser lost
	t.predict(step(0.8, 1e-6, 0));
	t.noFix({});
	EXPECT_EQ(t.searchNeeded(false), SearchScope::Window);
	int frames = 2;
	while (t.confirmed() && frames < 100)
	{
		t.predict(step(0.8, 1e-6, 0));
		t.noFix({});
		frames++;
	}
	// sigma = 0.02 m/m * d reaches 0.5 m after about 25 m (31 steps of 0.8 m).
	EXPECT_NEAR(frames * 0.8, 25.0, 1.0);
	EXPECT_EQ(t.searchNeeded(false), SearchScope::Whole);
	t.adoptPlace(poseAt(3, 0.05));
	t.predict(step(0.8));
	EXPECT_FALSE(t.confirmed());  // a new hypothesis
	EXPECT_EQ(t.searchNeeded(false), SearchScope::None);
}

// The fix covariance: the solver's scaled once, raised to the bootstrap's
// where that is larger beyond chance; the bootstrap's spread is not scaled
// again (before: max(solver, bootstrap) * cov_scale).
TEST(LocalisationStages, FixCovarianceIsNotInflatedTwice)
{
	const Matrix6d A = diag(0.01, 0.05);
	EXPECT_TRUE(fixCovariance(A, Matrix6d::Zero(), 4.0, 30).isApprox(4.0 * A));
	EXPECT_TRUE(fixCovariance(A, 3.0 * A, 4.0, 30).isApprox(4.0 * A));	// bootstrap below the scaled solver's
	EXPECT_TRUE(fixCovariance(A, 20.0 * A, 4.0, 30).isApprox(20.0 * A));  // above: the bootstrap's, not 80 A
	EXPECT_TRUE(fixCovariance(A, 20.0 * A, 4.0, 0).isApprox(4.0 * A));	// bootstrap off
}

TEST(LocalisationStages, FusionWeighsTheSolveAndThePredictionByTheirCovariances)
{
	// Equal covariances: half way, and half the covariance.
	const geometry::TPoseWithCov pred{ahead(10.0), diag(0.1, 1.0)};
	const geometry::TPoseWithCov solve{ahead(10.4), diag(0.1, 1.0)};
	const auto mid = fuseWithPrediction(solve, pred);
	EXPECT_NEAR(mid.T.translation().z(), 10.2, 1e-9);
	EXPECT_NEAR(mid.cov(2, 2), 0.5 * 0.01, 1e-12);
	// A solve weak in depth (far landmarks) and sharp across: the depth from
	// the prediction, the lateral offset from the solve.
	Matrix6d weakDepth = diag(0.01, 0.1);
	weakDepth(2, 2) = 0.5 * 0.5;
	geometry::TPoseWithCov off{ahead(10.5), weakDepth};
	off.T.translation().x() = 0.3;
	const auto f = fuseWithPrediction(off, pred);
	EXPECT_NEAR(f.T.translation().z(), 10.0 + 0.5 * 0.01 / (0.01 + 0.25), 1e-6);
	EXPECT_NEAR(f.T.translation().x(), 0.3 * 0.01 / (0.01 + 1e-4), 1e-6);
	EXPECT_LT(f.cov(2, 2), pred.cov(2, 2));
	// Not positive definite: the solve as it is.
	const auto same = fuseWithPrediction(solve, {ahead(10.0), Matrix6d::Zero() - Matrix6d::Identity()});
	EXPECT_TRUE(same.T.isApprox(solve.T));
}

TEST(LocalisationStages, DeadReckoningWindowCrossesASurveyBreak)
{
	// The synthetic road breaks after keyframe 14 (segment 1 predicted from
	// dead reckoning): along the chain the window stops there; in the map
	// frame it goes on into the next segment, within the same distance.
	const auto m = test::makeSyntheticMap(24, 4, 15);
	TKeyframePose dr;
	dr.valid = true;
	dr.kf = 14;
	dr.T_kf_live.translation() = Eigen::Vector3d(0, 0, 2.0);
	const auto along = m->keyframesAlongChain(14, 10, 10);
	EXPECT_EQ(along.back(), 14u);
	const auto w = keyframesAroundDeadReckoning(*m, dr, 10, 45);
	EXPECT_TRUE(std::is_sorted(w.begin(), w.end()));
	for (const uint32_t k : along) EXPECT_TRUE(std::binary_search(w.begin(), w.end(), k)) << k;
	EXPECT_TRUE(std::binary_search(w.begin(), w.end(), 15u));
	EXPECT_TRUE(std::binary_search(w.begin(), w.end(), 16u));
	// Along the chain from keyframe 14, or near the camera 2 m beyond it.
	const Eigen::Vector3d cam = (m->keyframe(14).T_map_kf * dr.T_kf_live).translation();
	for (const uint32_t k : w) EXPECT_LE((m->keyframe(k).T_map_kf.translation() - cam).norm(), 12.5) << k;
	EXPECT_FALSE(std::binary_search(w.begin(), w.end(), 23u)) << "18 m beyond the window";
}

// Places from the relocalisation, at system level: a place that agrees with
// the unconfirmed hypothesis it would replace is that hypothesis' next
// consistent frame (before, every search restarted it, so a run whose
// localisers could not hold the place never confirmed it); K agreeing places
// confirm it, and the K-th is a fix. A place that agrees with a confirmed
// track is a fix at once; an uncertain or disagreeing one never is.
TEST(LocalisationStages, AgreeingPlacesConfirmAHypothesisAsConsistentFramesDo)
{
	TTrackOptions o;
	constexpr int K = 2;
	Track t(o);
	const TKeyframePose first = poseAt(0.0, 0.03);
	EXPECT_EQ(t.placeFound(first, judged(first), true, K), PlaceOutcome::Hypothesis);
	EXPECT_EQ(t.hypothesisPlaces(), 1);
	EXPECT_FALSE(t.confirmed());
	// Two frames on (0.8 m each, no fix), a place where VO says the camera is.
	for (int i = 0; i < 2; i++)
	{
		t.predict(step(0.8));
		t.noFix({});
	}
	const TKeyframePose second = poseAt(1.62, 0.03);
	EXPECT_TRUE(placeAgrees(second, t.estimate(), identityLink, 16.81));
	// Uncertain (beyond the fix bounds): it continues the hypothesis, no fix.
	{
		Track u = t;
		EXPECT_EQ(u.placeFound(second, judged(second), false, K), PlaceOutcome::Hypothesis);
		EXPECT_EQ(u.hypothesisPlaces(), 2);
	}
	EXPECT_EQ(t.placeFound(second, judged(second), true, K), PlaceOutcome::Fix);
	EXPECT_EQ(t.hypothesisPlaces(), 0);
	t.predict(step(0.8));
	EXPECT_TRUE(t.confirmed());
	// A place 3 m from where the confirmed track is: a new hypothesis
	// (without the track's rank; see the next test).
	t.noFix({});
	const TKeyframePose far = poseAt(2.42 + 3.0, 0.03);
	EXPECT_FALSE(placeAgrees(far, t.estimate(), identityLink, 16.81));
	TTrackOptions unranked = o;
	unranked.confirmed_track_outranks_places = false;
	Track v(unranked);
	v.fix(poseAt(1.62, 0.03));
	v.predict(step(0.8));
	v.noFix({});
	EXPECT_EQ(v.placeFound(far, judged(far), true, K), PlaceOutcome::Hypothesis);
	EXPECT_EQ(v.hypothesisPlaces(), 1);
	EXPECT_FALSE(v.confirmed());
	// One that agrees with the confirmed track: a fix at once.
	const TKeyframePose near = poseAt(2.45, 0.03);
	EXPECT_EQ(t.placeFound(near, judged(near), true, K), PlaceOutcome::Fix);
	// With K = 3 the second agreeing place is not yet a fix.
	Track w(o);
	w.placeFound(first, judged(first), true, 3);
	w.predict(step(0.8));
	w.noFix({});
	const TKeyframePose next = poseAt(0.8, 0.03);
	EXPECT_EQ(w.placeFound(next, judged(next), true, 3), PlaceOutcome::Hypothesis);
	EXPECT_EQ(w.hypothesisPlaces(), 2);
}

// A place that contradicts a confirmed track replaces it only when it is the
// more certain of the two. One frame after a fix the track (a few cm) keeps
// its place against a lone verified place (its solve plus global_sigma_m): on
// the 301 m set such places were the start of wrong fixes (a wrong solve of
// the next frame agreed with the place and confirmed it, and the correct,
// tighter solve after it was refused as inconsistent). After metres of dead
// reckoning the track's drift outgrows the place and the place wins, so a
// wrong track is still left.
TEST(LocalisationStages, AConfirmedTrackOutranksALessCertainPlace)
{
	TTrackOptions o;
	constexpr int K = 2;
	Track t(o);
	t.fix(poseAt(0, 0.02));
	t.predict(step(0.8));
	t.noFix({});
	ASSERT_TRUE(t.confirmed());
	const TKeyframePose before = t.estimate();
	const TKeyframePose far = poseAt(0.8 + 0.6, 0.03);
	EXPECT_FALSE(placeAgrees(far, t.estimate(), identityLink, 16.81));
	EXPECT_EQ(t.placeFound(far, judged(far), true, K), PlaceOutcome::Outranked);
	EXPECT_TRUE(t.confirmed());
	EXPECT_EQ(t.hypothesisPlaces(), 0);
	EXPECT_TRUE(t.estimate().T_kf_live.isApprox(before.T_kf_live));
	// An uncertain place that agrees changes nothing either.
	const TKeyframePose vague = poseAt(0.8, 0.3);
	EXPECT_EQ(t.placeFound(vague, judged(vague), false, K), PlaceOutcome::Outranked);
	EXPECT_TRUE(t.confirmed());
	// A second place that agrees with the first outranked one through VO
	// (one frame on) overturns the track: two places against one track.
	{
		Track u = t;
		u.fix(poseAt(0.8, 0.02));
		u.predict(step(0.8));
		u.noFix({});
		const TKeyframePose p1 = poseAt(1.6 + 0.6, 0.03);
		EXPECT_EQ(u.placeFound(p1, judged(p1), true, K), PlaceOutcome::Outranked);
		u.predict(step(0.8));
		u.noFix({});
		const TKeyframePose elsewhere = poseAt(2.4 - 0.7, 0.03);
		EXPECT_EQ(u.placeFound(elsewhere, judged(elsewhere), true, K), PlaceOutcome::Outranked) << "agrees with neither";
		u.predict(step(0.8));
		u.noFix({});
		const TKeyframePose p2 = poseAt(3.2 - 0.7, 0.03);
		EXPECT_EQ(u.placeFound(p2, judged(p2), true, K), PlaceOutcome::Fix) << "agrees with the last rival";
		EXPECT_TRUE(u.estimate().T_kf_live.isApprox(p2.T_kf_live));
	}
	// 8 m of dead reckoning later (sigma ~0.16 m at 2 %/m) the place is the
	// more certain, and starts a hypothesis.
	for (int i = 0; i < 10; i++)
	{
		t.predict(step(0.8));
		t.noFix({});
	}
	ASSERT_TRUE(t.confirmed());
	const TKeyframePose later = poseAt(8.8 + 1.2, 0.03);
	EXPECT_FALSE(placeAgrees(later, t.estimate(), identityLink, 16.81));
	EXPECT_EQ(t.placeFound(later, judged(later), true, K), PlaceOutcome::Hypothesis);
	EXPECT_FALSE(t.confirmed());
	EXPECT_EQ(t.hypothesisPlaces(), 1);
}

// A place found in another segment of the map than the track (the survey's
// VO broke between them): it is judged through the localiser's keyframe
// link, which crosses the break with the map poses and a covariance that
// says so. The map's own relative pose is defined only within a segment and
// throws there: judged through it, such a place ended the run.
TEST(LocalisationStages, APlaceAcrossAVoBreakOfTheMapIsJudgedNotThrown)
{
	const auto m = test::makeSyntheticMap(24, 4, 15);
	TLocaliserOptions o;
	o.cross_segment_sigma_m = 2;
	o.cross_segment_sigma_deg = 5;
	const StereoLocaliser loc(*m, "mono", o);
	ASSERT_FALSE(m->sameSegment(14, 16));
	EXPECT_ANY_THROW(m->relativePose(14, 16));
	const auto link = loc.between(14, 16);
	EXPECT_TRUE(link.T.isApprox(m->keyframe(14).T_map_kf.inverse() * m->keyframe(16).T_map_kf, 1e-9));
	EXPECT_NEAR(std::sqrt(link.cov(0, 0)), 2.0, 1e-12);
	EXPECT_NEAR(std::sqrt(link.cov(5, 5)), 5.0 * kDeg, 1e-12);
	// Within a segment: the map's chain.
	EXPECT_TRUE(loc.between(3, 5).T.isApprox(m->relativePose(3, 5).T_a_b, 1e-9));

	// The track predicts 1 m past keyframe 14; the place is keyframe 16,
	// where the map frame puts that camera (agrees; the break's 2 m sigma
	// allows a few metres), or 12 m beyond (does not).
	const KeyframeLink through = [&loc](uint32_t a, uint32_t b) { return loc.between(a, b); };
	TKeyframePose pred = poseAt(1.0, 0.1, 14);
	const Eigen::Isometry3d T_16_cam = link.T.inverse() * pred.T_kf_live;
	TKeyframePose place = poseAt(0.0, 0.05, 16);
	place.T_kf_live = T_16_cam;
	EXPECT_NO_THROW(placeAgrees(place, pred, through, 16.81));
	EXPECT_TRUE(placeAgrees(place, pred, through, 16.81));
	place.T_kf_live.translation().z() += 12.0;
	EXPECT_FALSE(placeAgrees(place, pred, through, 16.81));
}

TEST(LocalisationStages, DisagreeingFixesOfOneFrameGoToTheMoreCertain)
{
	const double chi2 = 16.81;
	// Agreeing fixes: the policy order holds, even when the second is tighter.
	EXPECT_EQ(chooseFix({poseAt(1.00, 0.05), poseAt(1.03, 0.02)}, {0.05, 0.02}, identityLink, chi2), 0u);
	// 0.6 m apart at sigmas 0.12 and 0.02 m (4.9 sigma): the more certain.
	EXPECT_EQ(chooseFix({poseAt(1.0, 0.12), poseAt(1.6, 0.02)}, {0.12, 0.02}, identityLink, chi2), 1u);
	EXPECT_EQ(chooseFix({poseAt(1.0, 0.02), poseAt(1.6, 0.12)}, {0.02, 0.12}, identityLink, chi2), 0u);
	EXPECT_EQ(chooseFix({poseAt(1.0, 0.05)}, {0.05}, identityLink, chi2), 0u);
	// Through the link: the second fix in keyframe 1, 0.6 m ahead of keyframe 0.
	const KeyframeLink ahead06 = [](uint32_t a, uint32_t b) {
		geometry::TPoseWithCov l;
		l.T = ahead(a == b ? 0.0 : (a == 1 ? -0.6 : 0.6));
		l.cov = diag(0.001, 0.01);
		return l;
	};
	EXPECT_EQ(chooseFix({poseAt(1.0, 0.12), poseAt(0.4, 0.02, 1)}, {0.12, 0.02}, ahead06, chi2), 0u);
	EXPECT_EQ(chooseFix({poseAt(1.0, 0.12), poseAt(1.0, 0.02, 1)}, {0.12, 0.02}, ahead06, chi2), 1u);
	EXPECT_THROW(chooseFix({poseAt(1.0, 0.1)}, {}, identityLink, chi2), std::invalid_argument);
}

namespace
{
/** A channel's search of one live frame, as a localiser hands it on: `n`
 * landmarks of keyframe 0 between depths zMin and zMax, seen from the live
 * camera at T_kf_live with `noise_px` on each coordinate, expressed in
 * keyframe `kf` (through T_kf_0). */
TSearchedCorrespondences searchOf(
	const geometry::TStereoCalib& cal, const Eigen::Isometry3d& T_kf_live, int n, double zMin, double zMax,
	double noise_px, uint32_t seed, uint32_t kf = 0, const Eigen::Isometry3d& T_kf_0 = Eigen::Isometry3d::Identity())
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> U(0, 1);
	std::normal_distribution<double> N(0, noise_px);
	TSearchedCorrespondences s;
	s.kf = kf;
	for (int i = 0; i < n; i++)
	{
		const double z = zMin + (zMax - zMin) * U(rng);
		const Eigen::Vector3d P0((U(rng) - 0.5) * 0.8 * z, (U(rng) - 0.3) * 0.4 * z, z);
		geometry::TStereoCorrespondence c;
		c.P_ref = T_kf_0 * P0;
		c.calib_ref = cal;
		c.z_ref = cal.project(c.P_ref);
		c.z_curr = cal.project(T_kf_live.inverse() * P0) + Eigen::Vector3d(N(rng), N(rng), N(rng));
		cal.triangulate(c.z_curr.x(), c.z_curr.y(), c.z_curr.z(), c.P_curr);
		s.corr.push_back(c);
	}
	return s;
}
}  // namespace

// Two channels whose searches each hold too few matches for a solve of
// their own (12 near, 12 far; min_matches 15) solve together; the union is
// the same whichever keyframe a channel searched in (joined through the chain).
TEST(LocalisationStages, JointLocaliserSolvesTheUnionOfTwoChannelsSearches)
{
	const auto map = test::makeSyntheticMap(4, 4, 0);
	const geometry::TStereoCalib cal = map->calibration();
	TLocaliserOptions o;  // min_matches 15, min_inliers 20
	Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
	truth.translation() = Eigen::Vector3d(0.15, -0.02, 0.9);
	truth.linear() = Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()).toRotationMatrix();
	const auto near = searchOf(cal, truth, 12, 3, 8, 0.3, 1);
	const auto far = searchOf(cal, truth, 12, 20, 40, 0.3, 2);

	TLocaliserInput in;
	in.frame = 7;
	in.calib = cal;
	in.prediction = poseAt(0.9, 0.1);
	in.track_confirmed = true;
	in.motion = step(0.9);

	JointLocaliser one(*map, {"mono", "invariant"}, o);
	EXPECT_EQ(one.localise(in, {&near, nullptr}).status, LocaliserStatus::FewMatches) << "12 matches alone";
	JointLocaliser joint(*map, {"mono", "invariant"}, o);
	const TLocaliserResult r = joint.localise(in, {&near, &far});
	EXPECT_EQ(r.channel, "joint");
	EXPECT_EQ(r.matches, 24);
	EXPECT_EQ(r.status, LocaliserStatus::Ok) << toString(r.status);
	ASSERT_TRUE(r.solved);
	// 0.3 px on 24 landmarks, a third of them within 8 m: centimetres.
	EXPECT_LT((r.T_kf_live.translation() - truth.translation()).norm(), 0.05);
	EXPECT_GT(r.sigma_m, 0);

	// The far channel's search in keyframe 1: moved into keyframe 0 through
	// the map's chain, the same solve.
	const Eigen::Isometry3d T_1_0 = joint.between(1, 0).T;
	const auto farIn1 = searchOf(cal, truth, 12, 20, 40, 0.3, 2, 1, T_1_0);
	JointLocaliser across(*map, {"mono", "invariant"}, o);
	const TLocaliserResult a = across.localise(in, {&near, &farIn1});
	ASSERT_TRUE(a.solved);
	EXPECT_EQ(a.kf_id, 0u);
	EXPECT_LT((a.T_kf_live.translation() - r.T_kf_live.translation()).norm(), 1e-6);
	EXPECT_THROW(JointLocaliser(*map, {"mono"}, o), std::invalid_argument);
	EXPECT_THROW(JointLocaliser(*map, {"mono", "colour"}, o), std::exception);
}

// A channel's patch-pass matches confirm the pose they were found at: two
// channels whose rejected solves found 25 patches each at a pose 0.5 m off
// outvote their 15 descriptor matches each in the union. Taking the
// patches only of channels whose solve was accepted (of_fixes), the joint
// solve rests on the descriptor matches and finds the truth.
TEST(LocalisationStages, JointLocaliserTakesPatchMatchesOnlyOfAcceptedChannelSolves)
{
	const auto map = test::makeSyntheticMap(4, 4, 0);
	const geometry::TStereoCalib cal = map->calibration();
	TLocaliserOptions o;
	Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
	truth.translation() = Eigen::Vector3d(0.1, 0, 0.9);
	Eigen::Isometry3d off = truth;
	off.translation() += Eigen::Vector3d(0.3, 0, 0.4);	// 0.5 m
	auto channel = [&](uint32_t seed) {
		auto s = searchOf(cal, truth, 15, 3, 30, 0.3, seed);
		const auto patches = searchOf(cal, off, 25, 3, 30, 0.3, seed + 100);
		s.patch_from = s.corr.size();
		s.corr.insert(s.corr.end(), patches.corr.begin(), patches.corr.end());
		return s;
	};
	TLocaliserInput in;
	in.frame = 3;
	in.calib = cal;
	in.prediction = poseAt(0.9, 1.0);  // wide: the solve, not the prediction, decides
	in.track_confirmed = true;
	in.motion = step(0.9);
	auto jointWith = [&](JointPatchMatches take, bool fixA, bool fixB) {
		auto a = channel(1), b = channel(2);
		keepJointShare(a, fixA, take);
		keepJointShare(b, fixB, take);
		JointLocaliser joint(*map, {"mono", "invariant"}, o);
		return std::make_pair(joint.localise(in, {&a, &b}), a.corr.size() + b.corr.size());
	};
	const auto [all, nAll] = jointWith(JointPatchMatches::All, false, false);
	ASSERT_TRUE(all.solved);
	EXPECT_EQ(nAll, 80u);
	EXPECT_LT((all.T_kf_live.translation() - off.translation()).norm(), 0.05) << "the patches' pose wins the union";
	const auto [ofFixes, nOf] = jointWith(JointPatchMatches::OfFixes, false, false);
	ASSERT_TRUE(ofFixes.solved);
	EXPECT_EQ(nOf, 30u);
	EXPECT_LT((ofFixes.T_kf_live.translation() - truth.translation()).norm(), 0.05);
	EXPECT_EQ(jointWith(JointPatchMatches::OfFixes, true, false).second, 55u) << "an accepted channel's patches stay";
	EXPECT_EQ(jointWith(JointPatchMatches::None, true, true).second, 30u);
	// A search without a patch pass (patch_from at its end, or beyond) is kept whole.
	auto plain = searchOf(cal, truth, 12, 3, 30, 0.3, 5);
	plain.patch_from = 99;
	keepJointShare(plain, false, JointPatchMatches::None);
	EXPECT_EQ(plain.corr.size(), 12u);
}

// The system's cross-check, as a rejection: a fix that disagrees with a
// more certain one of the same frame is no fix, whatever the policy order;
// fixes that agree are all kept.
TEST(LocalisationStages, AFixContradictedByAMoreCertainOneIsRejected)
{
	const double chi2 = 16.81;
	using V = std::vector<bool>;
	// Agreeing: 3 cm apart at 2-5 cm.
	EXPECT_EQ(contradictedFixes({poseAt(1.00, 0.05), poseAt(1.03, 0.02)}, {0.05, 0.02}, identityLink, chi2), V({false, false}));
	// 0.6 m apart at 0.12 and 0.02 m: the less certain goes, first or second.
	EXPECT_EQ(contradictedFixes({poseAt(1.0, 0.12), poseAt(1.6, 0.02)}, {0.12, 0.02}, identityLink, chi2), V({true, false}));
	EXPECT_EQ(contradictedFixes({poseAt(1.0, 0.02), poseAt(1.6, 0.12)}, {0.02, 0.12}, identityLink, chi2), V({false, true}));
	// Three (a joint fix and two channels'): the most certain is kept, one
	// that agrees with it too, the one that agrees with neither goes.
	EXPECT_EQ(contradictedFixes(
				  {poseAt(1.6, 0.12), poseAt(1.0, 0.03), poseAt(1.02, 0.02)}, {0.12, 0.03, 0.02}, identityLink, chi2),
			  V({true, false, false}));
	// A wide fix that agrees with both of two that disagree with each other
	// is kept; of the two, the less certain goes.
	EXPECT_EQ(contradictedFixes(
				  {poseAt(1.0, 0.02), poseAt(1.3, 0.3), poseAt(1.6, 0.03)}, {0.02, 0.3, 0.03}, identityLink, chi2),
			  V({false, false, true}));
	EXPECT_TRUE(contradictedFixes({}, {}, identityLink, chi2).empty());
	EXPECT_THROW(contradictedFixes({poseAt(1.0, 0.1)}, {}, identityLink, chi2), std::invalid_argument);
}
