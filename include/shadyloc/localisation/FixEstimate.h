/* ShadyLoc — the estimate and accept stages every localiser shares: a
 * solve's covariance and figures, the bounds a fix must be within, the
 * acceptance call, and the link between two keyframes its tests use.
 * StereoLocaliser runs them on one channel's correspondences, JointLocaliser
 * on the union of several channels' (docs/localisation.md, "One solve over
 * both channels").
 */
#pragma once

#include <shadyloc/localisation/StereoLocaliser.h>

#include <cstddef>
#include <vector>

namespace shadyloc::localisation
{
using geometry::rotationSigma;
using geometry::translationSigma;

/** The localiser's measurement model for the pose solver. */
geometry::TPoseSolverOptions solverOptionsFor(const TLocaliserOptions& o);

/** A solve's covariance as a fix carries it: the scaled solver's, at least
 * the bootstrap's over its inliers (fixCovariance). `seed` fixes the
 * resamples; with `threads` >= 2 they are solved on two threads, to the
 * same result. */
geometry::Matrix6d solveCovariance(
	const TLocaliserOptions& o, const geometry::TStereoCalib& calib,
	const std::vector<geometry::TStereoCorrespondence>& corr, const vo::TRelativePoseOutput& po, uint32_t seed,
	int threads = 1);

/** Within the fix bounds (max_sigma_m, max_sigma_deg; 0 = none). */
bool withinFixBounds(const TLocaliserOptions& o, const geometry::Matrix6d& cov);

/** Fills a solved result from its solve po over corr (in r.kf_id's frame):
 * solved, the pose, its covariance and sigmas, the variance factor
 * (`threads` as solveCovariance). */
void describeSolve(
	const TLocaliserOptions& o, const geometry::TStereoCalib& calib,
	const std::vector<geometry::TStereoCorrespondence>& corr, const vo::TRelativePoseOutput& po, size_t frame,
	TLocaliserResult& r, int threads = 1);

/** The accept stage on a described solve: the fix bounds, then the tests of
 * `accept` against the input's prediction and motion; sets r.status, the
 * tests' statistics and r.consistent. */
void acceptSolve(
	FixAcceptance& accept, const TLocaliserOptions& o, const TLocaliserInput& in, const KeyframeLink& link,
	TLocaliserResult& r);

/** T_a_b with covariance through the map's chain, or through map poses plus
 * the cross-segment covariance of `o` when a and b are in different segments. */
geometry::TPoseWithCov keyframeLink(const CKeyframeMap& map, const TLocaliserOptions& o, uint32_t a, uint32_t b);

/** A correspondence with a landmark of keyframe k moved into keyframe ref's
 * frame (T_ref_k); its measurement there is the landmark's projection (the
 * two-view adjustment needs one). False when it lies behind ref's camera. */
bool intoReference(
	geometry::TStereoCorrespondence& corr, const Eigen::Isometry3d& T_ref_k, const geometry::TStereoCalib& calibKf);

}  // namespace shadyloc::localisation
