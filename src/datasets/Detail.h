/* ShadyLoc — private helpers of the importers (not installed). */
#pragma once

#include <shadyloc/datasets/Common.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/Tum.h>

#include <mrpt/core/Clock.h>
#include <mrpt/system/COutputLogger.h>
#include <mrpt/system/CTicTac.h>

#include <opencv2/core/mat.hpp>

#include <memory>
#include <string>
#include <vector>

namespace shadyloc::datasets::detail
{
/** Reads an 8-bit image as stored (BGR colour, or grey; alpha dropped).
 * Throws DatasetError "<what>: cannot read image '<path>'" on failure. */
cv::Mat readImage(const std::string& path, const std::string& what);

/** The mrpt::Clock tick (100 ns) nearest to t [s since Unix epoch]
 * (Clock::fromDouble truncates, which can lose a tick). */
mrpt::Clock::time_point timestampFromSeconds(double t);

/** strtod of the whole token; DatasetError naming `where` otherwise. */
double parseDouble(const std::string& token, const std::string& where);

/** One timestamp [s] per non-empty line (first column; '#' comments). */
std::vector<double> readTimes(const std::string& path);

/** Throws DatasetError naming `path` and the frame (index and both times)
 * if a timestamp is not after the one before it; `order` says what the
 * frames are ordered by, for the message. */
void checkTimesIncrease(const std::vector<double>& times, const std::string& path, const std::string& order);

/** Turns image pairs into CObservationStereoImages in an atomic rawlog, and
 * ground truth into a TUM file beside it, all or nothing. */
class StereoSink
{
   public:
	StereoSink(
		const std::string& outRawlog, const TImportOptions& opts, mrpt::system::COutputLogger& log);

	/** Calibration of every frame; image sizes must match ncols x nrows. */
	void setCalibration(
		const mrpt::img::TCamera& left, const mrpt::img::TCamera& right, double baseline_m);

	/** Checks sizes (error names `frameName`), builds and writes one frame. */
	void add(const cv::Mat& left, const cv::Mat& right, double t, const std::string& frameName);

	/** Declares an input of the import (file or folder): no output may replace it. */
	void addInput(const std::string& path, const std::string& what);

	/** Ground truth to write on commit() (empty: none). */
	io::Trajectory groundTruth;

	/** Writes the ground truth (if any), then renames the rawlog into place. */
	TImportResult commit();

	size_t frames() const { return m_frames; }

   private:
	TImportOptions m_opts;
	mrpt::system::COutputLogger& m_log;
	io::OutputTransaction m_outputs;  //!< rawlog, images folder, ground truth: together
	io::RawlogWriter m_writer;
	TImportResult m_result;
	size_t m_frames = 0;
	mrpt::system::CTicTac m_timer;
};

}  // namespace shadyloc::datasets::detail
