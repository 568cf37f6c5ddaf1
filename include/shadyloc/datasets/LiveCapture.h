/* ShadyLoc — stereo frames as they arrive from what OpenCV's VideoCapture
 * opens (a camera device, a video file, an image sequence such as
 * "frames/%06d.png"): one side-by-side source (left half | right half) or
 * two sources (left, right), with a rectified calibration .ini (the folder
 * importer's format, TFolderCalib). Frames become colour stereo observations
 * (CObservationStereoImages), the input every command already takes.
 *
 * A grabber thread reads ahead into a bounded queue. A camera does not wait
 * for the localiser: when the queue is full the oldest frame is dropped and
 * counted (never queued without bound). A file or image sequence waits for
 * the reader instead, so every frame is localised, unless `realtime` plays it
 * at its frame rate as a camera would.
 */
#pragma once

#include <shadyloc/datasets/Folder.h>

#include <mrpt/obs/CObservationStereoImages.h>

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace cv
{
class VideoCapture;
}

namespace shadyloc::datasets
{
struct TLiveCaptureOptions
{
	/** What VideoCapture opens: a device number ("0"), a video file or an
	 * image sequence pattern ("dir/%06d.png"). */
	std::string source;
	/** The right camera's source; "" = `source` is side by side. */
	std::string rightSource;
	std::string calibIni;  //!< rectified calibration (TFolderCalib)
	std::string sensorLabel = "LIVE_CAMERA";
	/** Frame rate for the timestamps of a file or sequence (frame i at
	 * i / fps) and for `realtime` [Hz]. */
	double fps = 10;
	/** Play a file at its frame rate, dropping what the reader misses. */
	bool realtime = false;
	size_t queue = 2;  //!< frames read ahead at most
};

/** Whether `source` names a camera device (a number, or /dev/video*). */
bool isCameraDevice(const std::string& source);

class LiveCapture
{
   public:
	/** Opens the sources and reads the calibration; DatasetError naming the
	 * source or the file (and key) at fault. Starts grabbing. */
	explicit LiveCapture(const TLiveCaptureOptions& o);
	~LiveCapture();
	LiveCapture(const LiveCapture&) = delete;
	LiveCapture& operator=(const LiveCapture&) = delete;

	/** The next frame, waiting for it; nullptr at the end of a file or
	 * sequence. Throws the grabber's error (naming source and frame). */
	mrpt::obs::CObservationStereoImages::Ptr next();

	size_t grabbed() const;	 //!< frames read from the source so far
	size_t dropped() const;	 //!< ... of which dropped because the reader was behind
	/** "'SOURCE'" or "'LEFT' + 'RIGHT'", for messages. */
	const std::string& name() const { return m_name; }
	bool dropsWhenBehind() const { return m_dropWhenBehind; }

   private:
	void grabLoop();
	/** Reads one frame; false at the end. Throws DatasetError. */
	bool readFrame(cv::Mat& left, cv::Mat& right);
	mrpt::obs::CObservationStereoImages::Ptr makeObservation(const cv::Mat& left, const cv::Mat& right, size_t index) const;
	void push(mrpt::obs::CObservationStereoImages::Ptr obs);

	TLiveCaptureOptions m_opts;
	TFolderCalib m_calib;
	std::string m_name;
	bool m_dropWhenBehind = false;
	std::unique_ptr<cv::VideoCapture> m_left, m_right;

	mutable std::mutex m_mutex;
	std::condition_variable m_changed;
	std::deque<mrpt::obs::CObservationStereoImages::Ptr> m_queue;
	bool m_ended = false, m_stop = false;
	std::exception_ptr m_error;
	size_t m_grabbed = 0, m_dropped = 0;
	std::thread m_thread;
};

}  // namespace shadyloc::datasets
