/* ShadyLoc — building a keyframe map from a survey run: one VO chain (the
 * monochrome VO's, the more accurate) decides where the map's keyframes are;
 * at those frames every channel's stereo measurements are stored, so both
 * localisers localise against the same keyframe poses (McManus et al. 2014,
 * Section II). Map keyframes are chosen by the map's own spacing options,
 * independent of the VO's internal keyframes; the relative transform between
 * consecutive map keyframes and its covariance are composed along the VO's
 * keyframe chain. A VO re-initialisation (a break) starts a new segment.
 *
 * The `survey` area joins the VO (which makes the chain) and the map (which
 * stores it): the map holds the keyframe data type the VO fills, so `vo`
 * includes `map`, and the builder, which needs both, cannot live in `map`
 * without a cycle (docs/architecture.md).
 */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/CObservationFilter.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/system/COutputLogger.h>

#include <optional>

namespace shadyloc::survey
{
/** What the map records of a channel: the filter that made its images (for
 * a filtered rawlog the filter its record names, not the config's) and the
 * feature options the channel's descriptors were made with. */
map::TChannelParams channelParams(
	const std::string& label, const CObservationFilter& madeBy, const features::TStereoFeatureOptions& fo);

/** Keeps at most `keep` measurements (all if keep <= 0 or fewer), spread
 * over the image: the image is cut into cols x rows buckets and the buckets
 * take turns giving up their strongest remaining corner (FAST response, then
 * stereo correlation), so the kept landmarks cover the view instead of
 * clustering on the most textured object. Order of the result: by bucket
 * round, stable. */
std::vector<features::TStereoMeasurement> selectLandmarks(
	const std::vector<features::TStereoMeasurement>& all, int keep, int cols, int rows, int width, int height);

class CSurveyBuilder : public mrpt::system::COutputLogger
{
   public:
	/** The map must be set up (CKeyframeMap::setup); its options give the
	 * keyframe spacing and the landmarks per keyframe. */
	CSurveyBuilder(CKeyframeMap& map, const std::string& runName);

	/** After the chain's VO processed a frame: `res` its result,
	 * `voKeyframes` the VO's keyframes now, `voKeyframesBefore` their count
	 * before the frame. True when this frame becomes a map keyframe: then
	 * call addKeyframe() with every channel's measurements of this frame. */
	bool offer(const vo::TFrameResult& res, const std::vector<vo::TKeyframe>& voKeyframes, size_t voKeyframesBefore);

	/** Adds the frame last offered (and accepted) with its measurements per
	 * channel (in the map's channel order), thinned by selectLandmarks, and
	 * its ground-truth pose if known. */
	void addKeyframe(
		const std::vector<std::vector<features::TStereoMeasurement>>& perChannel,
		const std::optional<Eigen::Isometry3d>& T_gt_kf = std::nullopt);

	size_t breaks() const { return m_breaks; }	//!< VO breaks seen (new segments)

   private:
	CKeyframeMap& m_map;
	uint16_t m_run;
	size_t m_breaks = 0;
	bool m_haveOrigin = false;
	Eigen::Isometry3d m_T_world_map = Eigen::Isometry3d::Identity();  //!< VO world -> map frame
	uint32_t m_segment = 0;
	bool m_segmentOpen = false;	 //!< a map keyframe exists in the current segment
	bool m_predictedSegment = false;  //!< the current segment started after a break
	// The last map keyframe, as seen by the VO chain: reference VO keyframe and pose in it.
	size_t m_lastRef = 0;
	Eigen::Isometry3d m_T_ref_last = Eigen::Isometry3d::Identity();
	geometry::Matrix6d m_cov_ref_last = geometry::Matrix6d::Zero();
	Eigen::Isometry3d m_T_map_last = Eigen::Isometry3d::Identity();
	// The frame accepted by offer(), waiting for addKeyframe().
	struct TPending
	{
		bool valid = false;
		vo::TFrameResult res;
		size_t ref = 0;
		Eigen::Isometry3d T_ref_f = Eigen::Isometry3d::Identity();
		geometry::Matrix6d cov_ref_f = geometry::Matrix6d::Zero();
		Eigen::Isometry3d T_prev_f = Eigen::Isometry3d::Identity();
		geometry::Matrix6d cov_prev_f = geometry::Matrix6d::Zero();
		bool newSegment = false;
	} m_pending;
};

}  // namespace shadyloc::survey
