/* ShadyLoc — stereo frames from VideoCapture (see LiveCapture.h). */
#include <shadyloc/datasets/LiveCapture.h>

#include "Detail.h"

#include <mrpt/system/datetime.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>

namespace shadyloc::datasets
{
namespace
{
bool isNumber(const std::string& s)
{
	return !s.empty() && s.size() < 6 && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

std::unique_ptr<cv::VideoCapture> open(const std::string& source)
{
	auto cap = std::make_unique<cv::VideoCapture>();
	const bool ok = isNumber(source) ? cap->open(std::stoi(source)) : cap->open(source);
	if (!ok || !cap->isOpened())
		throw DatasetError(
			"live source '" + source +
			"': VideoCapture cannot open it (a device number, a video file, or an image sequence such as "
			"dir/%06d.png)");
	return cap;
}

/** Colour BGR of a captured image (grey and BGRA sources too). */
cv::Mat toBgr(const cv::Mat& m)
{
	if (m.channels() == 3) return m;
	cv::Mat out;
	cv::cvtColor(m, out, m.channels() == 1 ? cv::COLOR_GRAY2BGR : cv::COLOR_BGRA2BGR);
	return out;
}

}  // namespace

bool isCameraDevice(const std::string& source)
{
	return isNumber(source) || source.rfind("/dev/video", 0) == 0;
}

LiveCapture::LiveCapture(const TLiveCaptureOptions& o) : m_opts(o)
{
	if (o.source.empty()) throw DatasetError("live source: none given");
	if (!(o.fps > 0)) throw DatasetError("live source '" + o.source + "': the frame rate must be > 0");
	if (o.queue < 1) throw DatasetError("live source '" + o.source + "': the queue must hold at least one frame");
	m_calib = TFolderCalib::FromFile(o.calibIni);
	m_name = "'" + o.source + "'" + (o.rightSource.empty() ? std::string() : " + '" + o.rightSource + "'");
	m_dropWhenBehind = isCameraDevice(o.source) || o.realtime;
	m_left = open(o.source);
	if (!o.rightSource.empty()) m_right = open(o.rightSource);
	m_thread = std::thread([this] { grabLoop(); });
}

LiveCapture::~LiveCapture()
{
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		m_stop = true;
	}
	m_changed.notify_all();
	if (m_thread.joinable()) m_thread.join();
}

bool LiveCapture::readFrame(cv::Mat& left, cv::Mat& right)
{
	const std::string at = "live source " + m_name + ": frame " + std::to_string(m_grabbed);
	cv::Mat a;
	if (!m_left->read(a) || a.empty()) return false;
	const auto W = int(m_calib.width), H = int(m_calib.height);
	if (m_right)
	{
		cv::Mat b;
		if (!m_right->read(b) || b.empty())
			throw DatasetError(at + ": the right source ended before the left one");
		left = toBgr(a);
		right = toBgr(b);
	}
	else
	{
		if (a.cols != 2 * W || a.rows != H)
			throw DatasetError(
				at + ": " + std::to_string(a.cols) + "x" + std::to_string(a.rows) +
				" px, expected side by side 2 x " + std::to_string(W) + "x" + std::to_string(H) + " (calibration '" +
				m_opts.calibIni + "')");
		const cv::Mat bgr = toBgr(a);
		left = bgr(cv::Rect(0, 0, W, H)).clone();
		right = bgr(cv::Rect(W, 0, W, H)).clone();
	}
	for (const auto* m : {&left, &right})
		if (m->cols != W || m->rows != H)
			throw DatasetError(
				at + ": an image is " + std::to_string(m->cols) + "x" + std::to_string(m->rows) + " px, the calibration '" +
				m_opts.calibIni + "' says " + std::to_string(W) + "x" + std::to_string(H));
	return true;
}

mrpt::obs::CObservationStereoImages::Ptr LiveCapture::makeObservation(
	const cv::Mat& left, const cv::Mat& right, size_t index) const
{
	auto obs = std::make_shared<mrpt::obs::CObservationStereoImages>();
	obs->sensorLabel = m_opts.sensorLabel;
	// A camera's frames are stamped when they arrive; a file's by its rate,
	// so that a file gives the same timestamps on every run.
	obs->timestamp = isCameraDevice(m_opts.source) ? mrpt::Clock::now()
												   : detail::timestampFromSeconds(double(index) / m_opts.fps);
	obs->leftCamera = m_calib.leftCamera();
	obs->rightCamera = m_calib.rightCamera();
	obs->leftCamera.cameraName = "left";
	obs->rightCamera.cameraName = "right";
	obs->rightCameraPose = mrpt::poses::CPose3DQuat(mrpt::poses::CPose3D(m_calib.baseline_m, 0, 0, 0, 0, 0));
	obs->imageLeft = mrpt::img::CImage(left, mrpt::img::DEEP_COPY);
	obs->imageRight = mrpt::img::CImage(right, mrpt::img::DEEP_COPY);
	obs->hasImageRight = true;
	return obs;
}

void LiveCapture::push(mrpt::obs::CObservationStereoImages::Ptr obs)
{
	std::unique_lock<std::mutex> lk(m_mutex);
	if (m_dropWhenBehind)
	{
		// A camera does not wait: the reader gets the newest frames.
		while (m_queue.size() >= m_opts.queue)
		{
			m_queue.pop_front();
			m_dropped++;
		}
	}
	else
		m_changed.wait(lk, [&] { return m_stop || m_queue.size() < m_opts.queue; });
	m_queue.push_back(std::move(obs));
	m_grabbed++;
	m_changed.notify_all();
}

void LiveCapture::grabLoop()
{
	const auto period = std::chrono::duration<double>(1.0 / m_opts.fps);
	auto due = std::chrono::steady_clock::now();
	try
	{
		cv::Mat l, r;
		for (size_t i = 0;; i++)
		{
			{
				std::lock_guard<std::mutex> lk(m_mutex);
				if (m_stop) break;
			}
			if (!readFrame(l, r)) break;
			push(makeObservation(l, r, i));
			if (m_opts.realtime && !isCameraDevice(m_opts.source))
			{
				due += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
				std::this_thread::sleep_until(due);
			}
		}
	}
	catch (...)
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		m_error = std::current_exception();
	}
	std::lock_guard<std::mutex> lk(m_mutex);
	m_ended = true;
	m_changed.notify_all();
}

mrpt::obs::CObservationStereoImages::Ptr LiveCapture::next()
{
	std::unique_lock<std::mutex> lk(m_mutex);
	m_changed.wait(lk, [&] { return !m_queue.empty() || m_ended; });
	if (!m_queue.empty())
	{
		auto obs = std::move(m_queue.front());
		m_queue.pop_front();
		m_changed.notify_all();
		return obs;
	}
	if (m_error) std::rethrow_exception(m_error);
	return nullptr;
}

size_t LiveCapture::grabbed() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_grabbed;
}

size_t LiveCapture::dropped() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_dropped;
}

}  // namespace shadyloc::datasets
