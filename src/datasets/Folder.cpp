/* ShadyLoc — folders of left/right images + calibration .ini -> rawlog. */
#include <shadyloc/datasets/Folder.h>

#include "Detail.h"

#include <shadyloc/core/Options.h>

#include <mrpt/config/CConfigFile.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace fs = std::filesystem;

namespace shadyloc::datasets
{
std::vector<std::string> listImages(const std::string& dir)
{
	if (!fs::is_directory(dir)) throw DatasetError("'" + dir + "': no such image directory");
	static const char* exts[] = {".png", ".jpg", ".jpeg", ".ppm", ".pgm", ".bmp", ".tif", ".tiff"};
	std::vector<std::string> out;
	for (const auto& e : fs::directory_iterator(dir))
	{
		if (!e.is_regular_file()) continue;
		std::string ext = e.path().extension().string();
		std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
		if (std::find(std::begin(exts), std::end(exts), ext) != std::end(exts))
			out.push_back(e.path().string());
	}
	std::sort(out.begin(), out.end());
	return out;
}

void TFolderCalib::TCameraKeys::keys(core::KeyVisitor& v)
{
	using core::Range;
	v.renamed({{"fx", "fx_px"}, {"fy", "fy_px"}, {"cx", "cx_px"}, {"cy", "cy_px"}});
	v("fx_px", fx, "px", Range::above(0), "focal length along x");
	v("fy_px", fy, "px", Range::above(0), "focal length along y");
	v("cx_px", cx, "px", Range::any(), "principal point x");
	v("cy_px", cy, "px", Range::any(), "principal point y");
}

void TFolderCalib::TStereoKeys::keys(core::KeyVisitor& v)
{
	using core::Range;
	v.renamed({{"width", "width_px"}, {"height", "height_px"}});
	v("baseline_m", baseline_m, "m", Range::above(0), "right camera centre at +baseline_m along the left camera's x axis");
	v("width_px", width, "px", Range::atLeast(1), "every image must be width x height");
	v("height_px", height, "px", Range::atLeast(1), "");
}

namespace
{
/** Reads keys' section from s, then finishes it; required: each key must be there. */
template <typename Keys>
void readSection(core::SettingsSection& s, Keys keys, bool required)
{
	core::readKeys(s, keys);
	if (required)
		for (const auto& k : core::keyTexts(keys))
			if (!s.has(k.first)) s.fail(k.first, "missing");
	s.finish();
}
}  // namespace

void TFolderCalib::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string&)
{
	core::checkSections(c, {"left", "right", "stereo"}, "stereo calibration");
	core::SettingsSection left(c, "left"), right(c, "right"), stereo(c, "stereo");
	readSection(left, leftKeys(), true);
	// Any key missing in [right]: the left value.
	fx_r = fx_l, fy_r = fy_l, cx_r = cx_l, cy_r = cy_l;
	readSection(right, rightKeys(), false);
	readSection(stereo, stereoKeys(), true);
	core::validateAt(left, [&] { core::checkKeys(leftKeys()); });
	core::validateAt(right, [&] { core::checkKeys(rightKeys()); });
	core::validateAt(stereo, [&] { core::checkKeys(stereoKeys()); });
}

void TFolderCalib::dumpToTextStream(std::ostream& out) const
{
	core::SettingsWriter w(out);
	auto& self = core::keysOf(*this);
	w.section("left");
	core::writeKeys(w, self.leftKeys());
	w.section("right");
	core::writeKeys(w, self.rightKeys());
	w.section("stereo");
	core::writeKeys(w, self.stereoKeys());
}

namespace
{
mrpt::img::TCamera cameraOf(double fx, double fy, double cx, double cy, uint32_t w, uint32_t h)
{
	mrpt::img::TCamera c;
	c.ncols = w;
	c.nrows = h;
	c.setIntrinsicParamsFromValues(fx, fy, cx, cy);
	c.dist.fill(0);
	return c;
}
}  // namespace

mrpt::img::TCamera TFolderCalib::leftCamera() const { return cameraOf(fx_l, fy_l, cx_l, cy_l, width, height); }

mrpt::img::TCamera TFolderCalib::rightCamera() const { return cameraOf(fx_r, fy_r, cx_r, cy_r, width, height); }

TFolderCalib TFolderCalib::FromFile(const std::string& iniPath)
{
	if (!fs::is_regular_file(iniPath)) throw DatasetError("'" + iniPath + "': no such calibration file");
	mrpt::config::CConfigFile cfg(iniPath);
	TFolderCalib c;
	try
	{
		c.loadFromConfigFile(cfg, "");
	}
	catch (const std::exception& e)
	{
		throw DatasetError(core::withSource(iniPath, e.what()));
	}
	return c;
}

FolderImporter::FolderImporter() : mrpt::system::COutputLogger("shadyloc.import.folder") {}

TImportResult FolderImporter::run(
	const std::string& leftDir, const std::string& rightDir, const std::string& calibIni,
	const std::string& outRawlog)
{
	const auto calib = TFolderCalib::FromFile(calibIni);
	const auto filesL = listImages(leftDir), filesR = listImages(rightDir);
	if (filesL.empty()) throw DatasetError("'" + leftDir + "': no images");
	if (filesL.size() != filesR.size())
		throw DatasetError(
			"mismatched image counts: '" + leftDir + "' has " + std::to_string(filesL.size()) +
			" images, '" + rightDir + "' has " + std::to_string(filesR.size()));

	std::vector<double> times;
	if (!timesFile.empty())
	{
		times = detail::readTimes(timesFile);
		if (times.size() != filesL.size())
			throw DatasetError(
				"'" + timesFile + "' has " + std::to_string(times.size()) + " timestamps for " +
				std::to_string(filesL.size()) + " image pairs");
		// Frames are paired by sorted file name: their times must increase too.
		detail::checkTimesIncrease(times, timesFile, "the (sorted) image names");
	}
	else
	{
		if (!(rateHz > 0))
			throw DatasetError("folder import: give a frame rate > 0 (rate) or a timestamps file (times)");
		for (size_t i = 0; i < filesL.size(); i++) times.push_back(startTime + double(i) / rateHz);
	}

	size_t n = filesL.size();
	if (options.maxFrames > 0) n = std::min(n, options.maxFrames);
	MRPT_LOG_INFO_STREAM(
		"Folder import: " << filesL.size() << " pairs from '" << leftDir << "' + '" << rightDir
						  << "', importing " << n << ", baseline " << calib.baseline_m << " m");

	detail::StereoSink sink(outRawlog, options, *this);
	sink.addInput(leftDir, "left image folder");
	sink.addInput(rightDir, "right image folder");
	sink.addInput(calibIni, "calibration");
	if (!timesFile.empty()) sink.addInput(timesFile, "timestamps file");
	sink.setCalibration(calib.leftCamera(), calib.rightCamera(), calib.baseline_m);
	for (size_t i = 0; i < n; i++)
	{
		const std::string frame = "frame " + std::to_string(i) + " ('" +
								  fs::path(filesL[i]).filename().string() + "' / '" +
								  fs::path(filesR[i]).filename().string() + "')";
		const cv::Mat L = detail::readImage(filesL[i], frame + " left");
		const cv::Mat R = detail::readImage(filesR[i], frame + " right");
		sink.add(L, R, times[i], frame);
	}
	return sink.commit();
}

}  // namespace shadyloc::datasets
