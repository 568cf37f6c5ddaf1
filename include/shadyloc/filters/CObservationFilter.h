/* ShadyLoc — observation filters: derive a new image channel (monochrome,
 * illumination-invariant, linearised) from a colour camera observation.
 *
 * Filters are MRPT RTTI classes (namespace `shadyloc`, the name stored in
 * files), built by class name from an .ini file, serialisable with their
 * options. Each filter leaves its input untouched and returns a new stock
 * MRPT observation of the same type, sensor label + output_suffix, same
 * timestamp, calibration and poses: output rawlogs open in stock MRPT tools.
 */
#pragma once

#include <shadyloc/core/Options.h>
#include <shadyloc/io/BoundedReader.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/serialization/CSerializable.h>

#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace shadyloc
{
/** Base of every observation filter (template method: the base handles the
 * observation types, derived classes transform images). */
class CObservationFilter : public mrpt::serialization::CSerializable
{
	DEFINE_VIRTUAL_SERIALIZABLE(CObservationFilter)

   public:
	/** Options every filter has. */
	struct TCommonOptions
	{
		/** Appended to the source sensor label to name the derived channel. */
		std::string output_suffix;
		/** Comma-separated sensor labels this filter applies to; empty = every
		 * camera observation (CObservationImage, CObservationStereoImages). */
		std::string sensor_labels;

		void keys(core::KeyVisitor& v);	 //!< every key, declared once (core/Options.h)
		/** Throws std::invalid_argument "output_suffix: ..." for an empty suffix. */
		void validate() const;
	};
	TCommonOptions common;

	/** The derived filter's own keys, declared once (core/Options.h); with
	 * common's they drive loadFromConfig(), optionsAsIni(),
	 * imageOptionsAsIni(), describe(), validate() and the docs' tables. */
	virtual void keys(core::KeyVisitor&) = 0;
	/** Throws std::invalid_argument "key: why" for a bad value of an own key
	 * (default: the ranges and choices of keys()). */
	virtual void validate() const;

	/** Loads this filter's options from `section` strictly (core::SettingsSection:
	 * missing keys keep their defaults; a bad value or a key no filter option
	 * reads throws core::SettingsError naming the file, section and key). The
	 * key `class` is allowed: the pipeline reads it. */
	void loadFromConfig(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	/** Every option as "key = value" lines (comments on their own lines) that
	 * loadFromConfig() reads back to the same values. */
	std::string optionsAsIni() const;

	/** The options that decide the images as canonical "key = value" lines
	 * (core::SettingsWriter, no comments), leaving out what only changes the
	 * speed (parallel_eyes) and values without effect (gamma unless
	 * linearisation = gamma; keysNotDecidingImages()): loadFromConfig() reads
	 * them back to a filter that makes the same images, and two filters with
	 * the same class and the same text make the same images. A keyframe map
	 * records this of the filter that made each channel. */
	std::string imageOptionsAsIni() const;

	/** One line: the options that decide the images (for logs and warnings). */
	virtual std::string describe() const;
	/** True if this filter makes the same images as `o` from the same input:
	 * same class and image options (suffix, sensor labels, threading aside).
	 * A map and a live run must agree on this, or their channels differ. */
	virtual bool sameImagesAs(const CObservationFilter& o) const;

	/** True if obs is a camera observation this filter should process. */
	bool accepts(const mrpt::obs::CObservation& obs) const;

	/** The derived observation; obs must be accepted. Throws
	 * std::invalid_argument on an image the filter cannot use (for example a
	 * grey image given to a colour filter), naming the sensor and eye. */
	mrpt::obs::CObservation::Ptr apply(const mrpt::obs::CObservation& obs) const;

	/** Transforms the images of one frame (one or two eyes). The default
	 * calls transformImage() per eye; filters may do eyes in parallel. */
	virtual void transformImages(const std::vector<cv::Mat>& in, std::vector<cv::Mat>& out) const;

	/** One image: in is as stored by mrpt::img::CImage (BGR for colour). */
	virtual void transformImage(const cv::Mat& in, cv::Mat& out) const = 0;

   protected:
	/** Reads the derived filter's keys from s and validates them (the caller
	 * finishes s). Default: keys(), then validate(). */
	virtual void loadSpecificOptions(core::SettingsSection& s);
	/** Own keys whose values do not change the images (left out of imageOptionsAsIni()). */
	virtual std::vector<std::string> keysNotDecidingImages() const { return {}; }
	/** The own keys' "key = value" lines (comments dropped, trimmed), but leaveOut. */
	std::vector<std::string> specificOptionLines(const std::vector<std::string>& leaveOut = {}) const;
	/** Called after options change (to rebuild tables and the like). */
	virtual void onOptionsChanged() {}

	/** Largest serialised filter a reader accepts [bytes]: its data are a
	 * few options (io::BoundedReader; a corrupt length fails, not allocates). */
	static constexpr uint64_t kMaxSerializedBytes = 64 * 1024;
	/** Longest option string (suffix, sensor label list) a reader accepts [bytes]. */
	static constexpr size_t kMaxOptionStringBytes = 4096;
	/** A bounded reader over serializeFrom()'s archive, naming this class and version. */
	io::BoundedReader boundedReader(mrpt::serialization::CArchive& in, uint8_t version) const;

	void serializeCommon(mrpt::serialization::CArchive& out) const;
	void deserializeCommon(io::BoundedReader& in);
};

}  // namespace shadyloc
