/* ShadyLoc — folders of left/right images + calibration .ini -> rawlog. */
#include <shadyloc/datasets/Folder.h>

#include "Detail.h"

#include <shadyloc/core/Settings.h>

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

void TFolderCalib::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string&)
{
	core::checkSections(c, {"left", "right", "stereo"}, "stereo calibration");
	const std::vector<core::TRenamedKey> renamedIntrinsics = {
		{"fx", "fx_px"}, {"fy", "fy_px"}, {"cx", "cx_px"}, {"cy", "cy_px"}};
	auto need = [](core::SettingsSection& s, const char* key, auto& v) {
		if (!s.has(key)) s.fail(key, "missing");
		s.read(key, v);
	};
	core::SettingsSection left(c, "left"), right(c, "right"), stereo(c, "stereo");
	left.renamed(renamedIntrinsics);
	right.renamed(renamedIntrinsics);
	stereo.renamed({{"width", "width_px"}, {"height", "height_px"}});
	need(left, "fx_px", fx_l);
	need(left, "fy_px", fy_l);
	need(left, "cx_px", cx_l);
	need(left, "cy_px", cy_l);
	left.finish();
	// Any key missing in [right]: the left value.
	fx_r = fx_l, fy_r = fy_l, cx_r = cx_l, cy_r = cy_l;
	right.read("fx_px", fx_r);
	right.read("fy_px", fy_r);
	right.read("cx_px", cx_r);
	right.read("cy_px", cy_r);
	right.finish();
	need(stereo, "baseline_m", baseline_m);
	need(stereo, "width_px", width);
	need(stereo, "height_px", height);
	stereo.finish();
	auto focal = [](core::SettingsSection& s, const char* key, double f) {
		if (!(f > 0)) s.fail(key, "a focal length must be > 0 (pixels)");
	};
	focal(left, "fx_px", fx_l);
	focal(left, "fy_px", fy_l);
	focal(right, "fx_px", fx_r);
	focal(right, "fy_px", fy_r);
	if (!(baseline_m > 0)) stereo.fail("baseline_m", "must be > 0 (metres, right camera along +x)");
	if (width < 1) stereo.fail("width_px", "must be a positive integer (pixels)");
	if (height < 1) stereo.fail("height_px", "must be a positive integer (pixels)");
}

void TFolderCalib::dumpToTextStream(std::ostream& out) const
{
	core::SettingsWriter w(out);
	w.section("left");
	w.value("fx_px", fx_l);
	w.value("fy_px", fy_l);
	w.value("cx_px", cx_l);
	w.value("cy_px", cy_l);
	w.section("right");
	w.value("fx_px", fx_r);
	w.value("fy_px", fy_r);
	w.value("cx_px", cx_r);
	w.value("cy_px", cy_r);
	w.section("stereo");
	w.value("baseline_m", baseline_m, "right camera centre at +baseline_m along the left camera's x axis");
	w.value("width_px", width);
	w.value("height_px", height);
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
