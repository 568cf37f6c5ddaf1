/* ShadyLoc — shared importer code: options, image reading, the rawlog sink. */
#include "Detail.h"

#include <shadyloc/core/Options.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/ImageFile.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace shadyloc::datasets
{
void TImportOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	v.renamed(
		{{"sensorLabel", "sensor_label"},
		 {"externalImages", "external_images"},
		 {"maxFrames", "max_frames"},
		 {"progressEvery", "progress_every"}});
	v("sensor_label", sensorLabel, "", Range::any(), "label of the stereo observations");
	v("external_images", externalImages, "", Range::any(), "PNG files in <stem>_Images/ instead of inline images");
	v("max_frames", maxFrames, "", Range::any(), "0: all");
	v("progress_every", progressEvery, "", Range::any(), "log progress every this many frames, 0: never");
}

void TImportOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::loadKeys(*this, c, s);
}

void TImportOptions::dumpToTextStream(std::ostream& out) const { core::dumpKeys(*this, out); }

void TImportOptions::validate() const
{
	core::checkKeys(*this);
	if (sensorLabel.empty()) throw std::invalid_argument("sensor_label: must not be empty");
}

std::string groundTruthPathFor(const std::string& rawlogPath)
{
	const fs::path p(rawlogPath);
	return (p.parent_path() / (p.stem().string() + "_gt.tum")).string();
}

namespace detail
{
cv::Mat readImage(const std::string& path, const std::string& what)
{
	cv::Mat m;
	try
	{
		// Checked: a truncated file is an error, not rows filled grey.
		m = io::readImageFile(path, cv::IMREAD_UNCHANGED);
	}
	catch (const io::ImageFileError& e)
	{
		throw DatasetError(what + ": cannot read image " + e.what());
	}
	if (m.depth() != CV_8U)
		throw DatasetError(
			what + ": image '" + path + "' is not 8-bit per channel (only 8-bit images are imported)");
	if (m.channels() == 4) cv::cvtColor(m, m, cv::COLOR_BGRA2BGR);
	else if (m.channels() != 3 && m.channels() != 1)
		throw DatasetError(
			what + ": image '" + path + "' has " + std::to_string(m.channels()) +
			" channels (1, 3 or 4 expected)");
	return m;
}

mrpt::Clock::time_point timestampFromSeconds(double t)
{
	auto best = mrpt::Clock::fromDouble(t);
	double bestErr = std::abs(mrpt::Clock::toDouble(best) - t);
	for (int d : {-1, 1})
	{
		const auto c = best + mrpt::Clock::duration(d);
		const double e = std::abs(mrpt::Clock::toDouble(c) - t);
		if (e < bestErr) best = c, bestErr = e;
	}
	return best;
}

double parseDouble(const std::string& token, const std::string& where)
{
	const char* s = token.c_str();
	char* end = nullptr;
	errno = 0;
	const double v = std::strtod(s, &end);
	if (end == s || *end != '\0' || errno == ERANGE || !std::isfinite(v))
		throw DatasetError(where + ": '" + token + "' is not a (finite) number");
	return v;
}

std::vector<double> readTimes(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw DatasetError("'" + path + "': cannot open timestamps file");
	std::vector<double> t;
	std::string line;
	for (size_t n = 1; std::getline(f, line); n++)
	{
		std::istringstream ss(line);
		std::string tok;
		if (!(ss >> tok) || tok[0] == '#') continue;
		t.push_back(parseDouble(tok, "'" + path + "':" + std::to_string(n)));
	}
	return t;
}

void checkTimesIncrease(const std::vector<double>& times, const std::string& path, const std::string& order)
{
	// Frames are paired with their times by position: a repeated or earlier
	// time is a damaged or mismatched file, and breaks trajectories.
	for (size_t i = 1; i < times.size(); i++)
		if (!(times[i] > times[i - 1]))
		{
			char b[160];
			std::snprintf(
				b, sizeof b, ": timestamp #%zu (%.9f s) is not after #%zu (%.9f s): timestamps must increase with ", i,
				times[i], i - 1, times[i - 1]);
			throw DatasetError("'" + path + "'" + b + order);
		}
}

StereoSink::StereoSink(
	const std::string& outRawlog, const TImportOptions& opts, mrpt::system::COutputLogger& log)
	: m_opts(opts), m_log(log), m_writer(outRawlog, opts.externalImages, &m_outputs)
{
	m_result.rawlogPath = outRawlog;
}

void StereoSink::addInput(const std::string& path, const std::string& what)
{
	try
	{
		m_outputs.addInput(path, what);
	}
	catch (const std::invalid_argument& e)
	{
		throw DatasetError(e.what());
	}
}

void StereoSink::setCalibration(
	const mrpt::img::TCamera& left, const mrpt::img::TCamera& right, double baseline_m)
{
	m_result.leftCamera = left;
	m_result.rightCamera = right;
	m_result.leftCamera.cameraName = "left";
	m_result.rightCamera.cameraName = "right";
	m_result.rightCameraPose =
		mrpt::poses::CPose3DQuat(mrpt::poses::CPose3D(baseline_m, 0, 0, 0, 0, 0));
}

void StereoSink::add(const cv::Mat& left, const cv::Mat& right, double t, const std::string& frameName)
{
	const auto& lc = m_result.leftCamera;
	const auto& rc = m_result.rightCamera;
	auto check = [&](const cv::Mat& m, const mrpt::img::TCamera& c, const char* which) {
		if (uint32_t(m.cols) != c.ncols || uint32_t(m.rows) != c.nrows)
			throw DatasetError(
				frameName + ": " + which + " image is " + std::to_string(m.cols) + "x" +
				std::to_string(m.rows) + ", expected " + std::to_string(c.ncols) + "x" +
				std::to_string(c.nrows) + " (calibration / first frame)");
	};
	check(left, lc, "left");
	check(right, rc, "right");

	mrpt::obs::CObservationStereoImages obs;
	obs.sensorLabel = m_opts.sensorLabel;
	obs.timestamp = timestampFromSeconds(t);
	obs.leftCamera = lc;
	obs.rightCamera = rc;
	obs.rightCameraPose = m_result.rightCameraPose;
	obs.imageLeft = mrpt::img::CImage(left, mrpt::img::DEEP_COPY);
	obs.imageRight = mrpt::img::CImage(right, mrpt::img::DEEP_COPY);
	obs.hasImageRight = true;
	if (m_writer.externalImages())
	{
		char stem[64];
		std::snprintf(stem, sizeof(stem), "%s_%06zu", m_opts.sensorLabel.c_str(), m_frames);
		m_writer.externalise(obs.imageLeft, std::string(stem) + "_left.png");
		m_writer.externalise(obs.imageRight, std::string(stem) + "_right.png");
	}
	m_writer.write(obs);
	m_frames++;
	if (m_opts.progressEvery > 0 && m_frames % m_opts.progressEvery == 0)
		m_log.logFmt(
			mrpt::system::LVL_INFO, "  %zu frames imported (%.1f frames/s)", m_frames,
			m_frames / std::max(1e-9, m_timer.Tac()));
}

TImportResult StereoSink::commit()
{
	if (m_frames == 0) throw DatasetError("'" + m_result.rawlogPath + "': no frames to import");
	const std::string gtPath = groundTruthPathFor(m_result.rawlogPath);
	std::error_code ec;
	if (!groundTruth.empty())
	{
		std::string tmp;
		try
		{
			tmp = m_outputs.addFile(gtPath, "ground truth");
		}
		catch (const std::invalid_argument& e)
		{
			throw DatasetError(e.what());
		}
		io::writeTum(tmp, groundTruth, "ground truth of '" + fs::path(m_result.rawlogPath).filename().string() + "'");
		m_result.groundTruthPath = gtPath;
	}
	m_writer.commit();
	m_outputs.commit();	 // rawlog, images and ground truth together
	if (groundTruth.empty() && fs::exists(gtPath, ec))
	{
		// A ground truth left by an earlier import to the same path would now
		// describe another dataset.
		fs::remove(gtPath, ec);
		m_log.logFmt(mrpt::system::LVL_WARN, "removed stale ground truth '%s'", gtPath.c_str());
	}
	m_result.frames = m_frames;
	m_result.seconds = m_timer.Tac();
	return m_result;
}

}  // namespace detail
}  // namespace shadyloc::datasets
