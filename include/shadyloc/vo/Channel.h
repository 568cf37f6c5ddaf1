/* ShadyLoc — which grey image the VO runs on. The pipeline is the same for
 * both channels; only this conversion differs (config/vo.ini: [vo] channel =
 * mono | invariant, invariant parameters in the [invariant] section, the same
 * keys as the CFilterInvariant section of config/filters.ini). */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/vo/StereoVO.h>
#include <shadyloc/image/ColourTransforms.h>

#include <mrpt/config/CConfigFileBase.h>

#include <opencv2/core/mat.hpp>

#include <memory>
#include <string>

namespace shadyloc::vo
{
enum class Channel
{
	Mono,
	Invariant
};
Channel parseChannel(const std::string& s);	 //!< "mono" | "invariant" (or "inv")
std::string toString(Channel c);
/** Sensor-label suffix of this channel in filtered rawlogs ("_mono", "_inv"). */
std::string channelSuffix(Channel c);

class ChannelConverter
{
   public:
	ChannelConverter(
		Channel c, const image::InvariantParams& p = image::InvariantParams::FromAlphaBeta(0.48, 0.5065),
		image::ChannelOrder monoOrder = image::ChannelOrder::BGR);
	/** Channel from `[vo] channel` (unless `channel` is given), invariant
	 * parameters from section `invSection` (CFilterInvariant's keys). */
	static ChannelConverter FromConfig(
		const mrpt::config::CConfigFileBase& cfg, const std::string& channel = "",
		const std::string& invSection = "invariant");

	Channel channel() const { return m_channel; }
	const image::InvariantParams& invariantParams() const { return m_params; }

	/** Colour (CV_8UC3) to this channel's CV_8UC1. Mono passes grey input
	 * through; the invariant channel needs colour (throws otherwise). */
	void convert(const cv::Mat& colour, cv::Mat& grey) const;
	std::string asString() const;

   private:
	Channel m_channel;
	image::InvariantParams m_params;
	image::ChannelOrder m_order;
	std::shared_ptr<image::InvariantTransform> m_inv;
};

/** Feature options for channel c: section `base` ([features]), then the
 * keys of `base.<channel>` ([features.invariant], [features.mono]) if that
 * section exists override them. The invariant image has less contrast and more
 * pixel noise than the mono one, so it usually wants its own FAST threshold
 * and pre-smoothing. Throws std::invalid_argument naming the section at fault. */
features::TStereoFeatureOptions featureOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, Channel c, const std::string& base = "features");

/** VO options for channel c, the same way: section `base` ([vo]), then the
 * keys of `base.<channel>` ([vo.mono], [vo.invariant]) if present. */
TStereoVOOptions voOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, Channel c, const std::string& base = "vo");

}  // namespace shadyloc::vo
