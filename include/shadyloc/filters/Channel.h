/* ShadyLoc — image channels as filter objects.
 *
 * A channel (the monochrome or the illumination-invariant image the VO, the
 * map and the localisers run on) is the observation filter that produces it,
 * named by the .ini section that defines the filter. One section therefore
 * drives everything: `shadyloc filter` writes the channel's images into a
 * rawlog (sensor label + the filter's output_suffix) and records the filter;
 * the survey, `shadyloc vo --channel NAME` and the localisation read those
 * images, or run the same filter on the fly on an unfiltered rawlog
 * (ChannelFrameSource.h).
 *
 *   [invariant]                ; the channel "invariant" (also "inv", its suffix)
 *   class = CFilterInvariant
 *   output_suffix = _inv
 *   alpha = 0.48
 *   beta = 0.5065
 */
#pragma once

#include <shadyloc/filters/CObservationFilter.h>
#include <shadyloc/filters/FilterPipeline.h>

#include <mrpt/config/CConfigFileBase.h>

#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace shadyloc::filters
{
/** A channel: the filter that makes its images, under its name. */
struct TChannel
{
	std::string label;  //!< the channel's name: its filter's .ini section ("mono", "invariant")
	CObservationFilter::Ptr filter;	 //!< makes the channel's images

	/** The filter's output_suffix: the channel's observations in a filtered
	 * rawlog are labelled <camera label><suffix> ("CAMERA_inv"). */
	const std::string& suffix() const { return filter->common.output_suffix; }
	/** True if `name` names this channel: its label, or its suffix without
	 * the leading '_' ("inv" for "_inv"). */
	bool isNamed(const std::string& name) const;

	/** One image through the filter (colour as MRPT stores it, BGR, to the
	 * channel's grey image). Throws std::invalid_argument on an image the
	 * filter cannot use (e.g. a grey one for the invariant channel). */
	void convert(const cv::Mat& in, cv::Mat& out) const { filter->transformImage(in, out); }
	/** A stereo pair through the filter (both eyes at once, as the filter
	 * does them, e.g. the invariant filter on two threads). */
	void convertPair(const cv::Mat& l, const cv::Mat& r, cv::Mat& lo, cv::Mat& ro) const;

	/** "invariant (CFilterInvariant, suffix _inv: alpha=... beta=...)". */
	std::string asString() const;
};

/** The channels of a pipeline, labelled by their sections. */
std::vector<TChannel> channelsOf(const FilterPipeline& p);

/** The built-in channel called `name` (FilterPipeline::Default(): "mono" =
 * CFilterMonochrome, suffix _mono; "invariant" = CFilterInvariant, suffix
 * _inv, the paper's alpha and beta), or std::invalid_argument. */
TChannel defaultChannel(const std::string& name);

/** The channel called `name` as a config defines it:
 *  1. a filter of the config's [filters] pipeline (section name or suffix);
 *  2. else the section [name] (or, for a built-in channel's other name such
 *     as "inv", the built-in's section [invariant]), built by its `class` key
 *     through the filter factory, like the pipeline's sections; a built-in
 *     channel's section may leave `class` out;
 *  3. else the built-in channel of that name.
 * Throws std::invalid_argument naming `what` (the config file), the section
 * and key at fault, or the channel names it knows. */
TChannel channelFromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& name, const std::string& what);

/** How one rawlog gives a channel's images. */
struct TChannelInput
{
	std::string rawlog;	 //!< the rawlog
	/** The stereo label read: "<camera><suffix>" if the rawlog carries the
	 * channel's images, else the colour camera (empty: the first stereo
	 * label that is not a derived channel). */
	std::string sensorLabel;
	bool filtered = false;	//!< the rawlog carries the channel's images (else: filter on the fly)
	/** filtered: the filter its pipeline record says made those images (the
	 * record's filter with the channel's suffix); null if no record says. */
	CObservationFilter::Ptr recorded;
	bool hasRecord = false;	 //!< the rawlog starts with a filter pipeline record
	/** Suffixes of the derived channels the rawlog may hold (this channel's,
	 * its record's): a colour camera's label ends in none of them. */
	std::vector<std::string> derivedSuffixes;
};

/** Finds how to read `channel` from `rawlog`: its derived observations
 * (labelled <camera><suffix>, camera = `cameraLabel` if given) if the first
 * objects hold some, else the colour camera `cameraLabel` (or, when empty,
 * the first stereo label that is not a derived channel: derivedSuffixes),
 * through the channel's filter on the fly. Reads the pipeline record at the
 * head of a filtered rawlog. Throws io::RawlogError naming the file. */
TChannelInput resolveChannelInput(
	const std::string& rawlog, const TChannel& channel, const std::string& cameraLabel = "");

}  // namespace shadyloc::filters
