/* ShadyLoc — one solve over several channels' correspondences.
 *
 * The channel localisers search the map each in its own images; the joint
 * localiser takes what their searches found on the same frame (refined
 * correspondences, solved or not) and solves the union: one RANSAC, one
 * robust solve, the shared covariance and acceptance (FixEstimate.h), its
 * own failure-test state. The channels' strengths differ in where their
 * landmarks lie: the monochrome channel holds the near field (lane markings,
 * asphalt) that pins the translation, the invariant channel many far
 * landmarks that survive hard light and hold the rotation. The paper switched
 * rather than fused because its invariant estimates were noisier (McManus et
 * al. 2014, Section III); a joint solve lets each landmark count by its own
 * geometry instead (docs/localisation.md, "One solve over both channels").
 * Its options: [localiser], then [localiser.joint].
 */
#pragma once

#include <shadyloc/localisation/StereoLocaliser.h>

#include <string>
#include <vector>

namespace shadyloc::localisation
{
/** Which of a channel's patch-pass matches the joint localiser takes. The
 * patch pass finds matches where the channel's own solve (or the
 * prediction) puts them, so they confirm that pose whether it is right or
 * not; the descriptor matches are found without it. */
enum class JointPatchMatches
{
	All,	  //!< every channel's
	OfFixes,  //!< a channel's only where its own solve was accepted
	None	  //!< none: the descriptor matches alone
};

/** A channel's search cut to the share the joint localiser takes: its
 * descriptor matches, and its patch-pass matches (corr[patch_from..]) as
 * `take` says; `channelFix`: the channel's own solve was accepted. */
void keepJointShare(TSearchedCorrespondences& s, bool channelFix, JointPatchMatches take);

class JointLocaliser
{
   public:
	/** The label of its results (TLocaliserResult::channel). */
	static constexpr const char* kLabel = "joint";

	/** `channels` (two or more, each a map channel) name the localisers
	 * whose searches it joins. The map must outlive the localiser. It runs
	 * after the channels, when their threads are idle: with `threads` >= 2
	 * its bootstrap uses two (the same result as one). */
	JointLocaliser(
		const CKeyframeMap& map, const std::vector<std::string>& channels, const TLocaliserOptions& o,
		int threads = 1);

	/** One frame: `parts` are the channels' searches of this frame in
	 * channels() order (null or empty: that channel did not search). The
	 * union is solved in the first searching channel's keyframe. */
	TLocaliserResult localise(const TLocaliserInput& in, const std::vector<const TSearchedCorrespondences*>& parts);
	/** The result of a frame it was not run on (status NotRun); the system
	 * then starts its acceptance from the frame's fix (startFrom). */
	TLocaliserResult notRun(const TLocaliserInput& in) const;

	/** See StereoLocaliser::reset, startFrom, between. */
	void reset() { m_accept.reset(); }
	void forgetSolve() { m_accept.noSolve(); }
	void startFrom(size_t frame, const TKeyframePose& place) { m_accept.startFrom(frame, place); }
	geometry::TPoseWithCov between(uint32_t a, uint32_t b) const;

	const std::vector<std::string>& channels() const { return m_channels; }
	const TLocaliserOptions& options() const { return m_opts; }

   private:
	/** The parts' correspondences in keyframe `ref`'s frame. */
	std::vector<geometry::TStereoCorrespondence> unionIn(
		uint32_t ref, const std::vector<const TSearchedCorrespondences*>& parts) const;

	const CKeyframeMap& m_map;
	std::vector<std::string> m_channels;
	TLocaliserOptions m_opts;
	int m_threads;
	vo::RelativePoseEstimator m_estimator;
	FixAcceptance m_accept;
};

}  // namespace shadyloc::localisation
