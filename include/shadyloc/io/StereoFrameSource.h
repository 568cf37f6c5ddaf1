/* ShadyLoc — the stereo frames of one camera of a rawlog, one at a time.
 *
 * It reads either rawlog style (bare observations, or sensory frames), picks
 * one sensor label, loads external images (from this rawlog's own images
 * folder), checks that the calibration and image size stay those of the first
 * frame, and yields typed frames. Every error names the file, the object and
 * the frame. The checks of one camera's observations are StereoFrameChecker,
 * which the channels' frame source (filters/ChannelFrameSource.h) shares.
 * Images are yielded as stored: making channels from them is the filters'
 * business, not this reader's.
 */
#pragma once

#include <shadyloc/geometry/StereoCamera.h>
#include <shadyloc/io/Rawlog.h>

#include <mrpt/img/TStereoCamera.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/core/mat.hpp>

#include <functional>
#include <set>
#include <string>
#include <vector>

namespace shadyloc::io
{
/** One stereo frame. The images share pixels with the observation (no copy). */
struct TStereoFrame
{
	size_t index = 0;  //!< 0-based among the frames of the chosen label
	size_t object = 0;	//!< index of the rawlog object that held it
	double timestamp = 0;  //!< [s] since the Unix epoch (mrpt::Clock::toDouble)
	std::string sensorLabel;  //!< the observation's label
	cv::Mat left, right;  //!< CV_8UC1 grey or CV_8UC3 colour (BGR, as MRPT stores it)
	geometry::TStereoCalib calib;  //!< the rectified stereo model of the pair
	mrpt::img::TStereoCamera camera;  //!< the calibration as stored (intrinsics, distortion, size, right pose)
	mrpt::obs::CObservationStereoImages::Ptr obs;  //!< the observation itself
};

/** Which stereo observations to read. */
struct TStereoFrameSourceOptions
{
	/** Read this label only. Empty: the label of the first stereo observation
	 * that acceptLabel accepts (every label if acceptLabel is empty). */
	std::string sensorLabel;
	std::function<bool(const std::string& label)> acceptLabel;
};

/** What differs between two stored calibrations ("left intrinsics fx=...
 * (was ...)"), "" if nothing. Exact: every frame of one camera, and every
 * channel made from it, carries the same copied numbers. */
std::string calibrationDifference(const mrpt::img::TStereoCamera& a, const mrpt::img::TStereoCamera& b);

/** The checks every frame of one camera passes, in one place: a right
 * image, external images that load, a timestamp after the previous frame's,
 * non-empty left/right images of one size, a rectified pair, and the first
 * frame's calibration and image size. */
class StereoFrameChecker
{
   public:
	/** Fills f (all but index and object) from the observation and checks
	 * it. Throws RawlogError(where + what is wrong); `where` names file,
	 * object, frame and sensor ("'<file>': object #3: frame 2 (sensor 'C'): "). */
	void take(const mrpt::obs::CObservationStereoImages::Ptr& st, const std::string& where, TStereoFrame& f);
	size_t frames() const { return m_frames; }	//!< frames taken so far

   private:
	size_t m_frames = 0;
	double m_lastTime = 0;	//!< the previous frame's timestamp [s]
	// The first frame's, which every later frame must match.
	mrpt::img::TStereoCamera m_camera;
	geometry::TStereoCalib m_calib;
	cv::Size m_size;
};

/** Accepts labels ending in `suffix` and, if `base` is given, equal to
 * base + suffix: picks a derived channel ("CAMERA_inv") by its suffix. */
std::function<bool(const std::string&)> labelWithSuffix(const std::string& suffix, const std::string& base = "");
/** Accepts labels that end in none of `suffixes`: the source cameras of a
 * filtered rawlog, not their derived channels. */
std::function<bool(const std::string&)> labelWithoutSuffixes(const std::vector<std::string>& suffixes);

/** The label of the first stereo observation `accept` accepts within the
 * first `maxObjects` objects of a rawlog, or "" if there is none. */
std::string findStereoLabel(
	const std::string& rawlogPath, const std::function<bool(const std::string&)>& accept,
	size_t maxObjects = 200);

class StereoFrameSource
{
   public:
	/** Opens the rawlog (throws RawlogError naming it if missing). */
	explicit StereoFrameSource(const std::string& rawlogPath, const TStereoFrameSourceOptions& opts = {});

	/** The next frame into f; false at the end of the rawlog. Throws
	 * RawlogError "'<file>': object #<k>: frame <i> (sensor '<label>'): ..."
	 * on a missing right image, a timestamp not after the previous frame's,
	 * empty or mismatched images, a calibration or
	 * image size other than the first frame's, a pair that is not rectified,
	 * or any error of the reader. */
	bool next(TStereoFrame& f);

	/** The label being read ("" before the first frame if none was given). */
	const std::string& sensorLabel() const { return m_label; }
	size_t frames() const { return m_frames; }	//!< frames yielded so far
	/** Labels of the other observations seen (for "no frames" messages). */
	const std::set<std::string>& otherLabels() const { return m_otherLabels; }
	double progress() const { return m_reader.progress(); }	 //!< fraction of the file read
	const std::string& path() const { return m_reader.path(); }
	const RawlogReader& reader() const { return m_reader; }

	/** "'<path>': no stereo observations [labelled 'X'] (other labels: ...)":
	 * the message for a rawlog that gave no frames. */
	std::string noFramesMessage() const;

   private:
	RawlogReader m_reader;
	TStereoFrameSourceOptions m_opts;
	std::string m_label;
	size_t m_frames = 0;
	std::set<std::string> m_otherLabels;
	std::vector<mrpt::obs::CObservation::Ptr> m_pending;  //!< rest of the current sensory frame
	size_t m_pendingObject = 0;
	StereoFrameChecker m_check;
};

}  // namespace shadyloc::io
