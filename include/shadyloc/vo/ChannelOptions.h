/* ShadyLoc — the VO's options for one channel. The pipeline is the same for
 * every channel; a channel (filters/Channel.h: the filter that makes its
 * images) may override some of its options in sections of its own. */
#pragma once

#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/vo/StereoVO.h>

#include <mrpt/config/CConfigFileBase.h>

#include <string>

namespace shadyloc::vo
{
/** Feature options for the channel labelled `channel`: section `base`
 * ([features]), then the keys of `base.<channel>` ([features.invariant],
 * [features.mono]) if that section exists override them. The invariant image
 * has less contrast and more pixel noise than the mono one, so it usually
 * wants its own FAST threshold and pre-smoothing. Throws
 * std::invalid_argument naming the section at fault. */
features::TStereoFeatureOptions featureOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& base = "features");

/** VO options for the channel labelled `channel`, the same way: section
 * `base` ([vo]), then the keys of `base.<channel>` ([vo.mono],
 * [vo.invariant]) if present. */
TStereoVOOptions voOptionsFor(
	const mrpt::config::CConfigFileBase& cfg, const std::string& channel, const std::string& base = "vo");

}  // namespace shadyloc::vo
