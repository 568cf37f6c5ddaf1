/* ShadyLoc — a list of observation filters built from an .ini file, and the
 * streaming rawlog processor that applies it. */
#pragma once

#include <shadyloc/filters/CObservationFilter.h>

#include <mrpt/system/COutputLogger.h>

#include <string>
#include <vector>

namespace shadyloc::filters
{
/** Section and key naming the pipeline in an .ini file:
 *   [filters]
 *   pipeline = mono invariant     ; section names, applied in this order
 *   [mono]
 *   class = CFilterMonochrome     ; "shadyloc::" may be omitted
 */
constexpr const char* kPipelineSection = "filters";
/** Sensor label of the CObservationComment that records, at the head of an
 * output rawlog, the exact options that made its derived channels. */
constexpr const char* kRecordLabel = "shadyloc_filters";
/** First line of that record's text (CObservationComment does not store its
 * sensor label, so the text identifies it). */
constexpr const char* kRecordHeader = "# shadyloc filter pipeline record v1";

class FilterPipeline
{
   public:
	std::vector<CObservationFilter::Ptr> filters;
	/** Each filter's .ini section: the name of the channel it makes
	 * (filters/Channel.h). Empty, or one per filter. */
	std::vector<std::string> labels;

	/** The default: monochrome and invariant (paper's alpha, beta), labelled
	 * "mono" and "invariant" as in config/filters.ini. */
	static FilterPipeline Default();
	/** Builds from an .ini file; throws naming the file, section and key.
	 * Two filters that would write the same derived channel (same
	 * output_suffix for an overlapping set of sensors) are an error naming
	 * both sections. */
	static FilterPipeline FromConfigFile(const std::string& iniPath);
	static FilterPipeline FromConfig(const mrpt::config::CConfigFileBase& cfg, const std::string& what);
	/** Builds the filters of the given sections, each by its `class` key. */
	static FilterPipeline FromSections(
		const mrpt::config::CConfigFileBase& cfg, const std::vector<std::string>& sections,
		const std::string& what);
	/** The exact options of every filter, as an .ini text FromConfig() reads
	 * (sections named by the labels). */
	std::string asIni() const;
	/** labels[i], or "filter<i>" where there is none. */
	std::string label(size_t i) const;
};

/** What a run of the processor did. */
struct FilterRunStats
{
	size_t objectsIn = 0;			//!< top-level objects read
	size_t objectsOut = 0;			//!< top-level objects written
	size_t observationsFiltered = 0;  //!< camera observations that got channels
	size_t derivedObservations = 0;	//!< observations added
	double seconds = 0;
};

/** Streams a rawlog through a pipeline: every input object is written out
 * unchanged, each accepted camera observation followed by its derived
 * channels (in the same sensory frame, for rawlogs in that style). The output
 * starts with a record (kRecordLabel) of the pipeline's options. Writes
 * atomically; on any error throws naming the object and leaves no output.
 * Images the input stores externally are linked (or copied) into the
 * output's images folder, so the output stands on its own; the output's
 * images folder may not be the input's. A derived channel whose label the
 * input already holds (a filtered rawlog filtered again), or a filter whose
 * sensor_labels match no observation, is an error. */
class RawlogFilterProcessor : public mrpt::system::COutputLogger
{
   public:
	RawlogFilterProcessor();
	bool externalImages = false;	 //!< write derived images as PNG files
	double progressPeriodSeconds = 2.0;	 //!< how often to log progress
	/** Further inputs the output may not replace (e.g. the pipeline's .ini). */
	std::vector<std::string> otherInputs;

	FilterRunStats run(
		const std::string& inPath, const std::string& outPath, const FilterPipeline& pipeline);
};

/** The pipeline record (an .ini text FilterPipeline::FromConfig reads) at the
 * head of a filtered rawlog, or "" if none. Reads only the first few objects. */
std::string readPipelineRecord(const std::string& rawlogPath);

}  // namespace shadyloc::filters
