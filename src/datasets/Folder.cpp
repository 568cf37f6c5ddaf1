/* ShadyLoc — folders of left/right images + calibration .ini -> rawlog. */
#include <shadyloc/datasets/Folder.h>

#include "Detail.h"

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
	auto need = [&](const std::string& sect, const std::string& key) {
		if (!c.keyExists(sect, key))
			throw DatasetError("[" + sect + "] " + key + ": missing");
		// Trailing ";" / "#" / "//" comments are documentation in our .ini files.
		std::string v = c.read_string(sect, key, "");
		for (const char* mark : {";", "#", "//"}) v = v.substr(0, v.find(mark));
		v.erase(0, v.find_first_not_of(" \t"));
		v.erase(v.find_last_not_of(" \t\r") + 1);
		return detail::parseDouble(v, "[" + sect + "] " + key);
	};
	auto opt = [&](const std::string& sect, const std::string& key, double def) {
		return c.keyExists(sect, key) ? need(sect, key) : def;
	};
	fx_l = need("left", "fx");
	fy_l = need("left", "fy");
	cx_l = need("left", "cx");
	cy_l = need("left", "cy");
	fx_r = opt("right", "fx", fx_l);
	fy_r = opt("right", "fy", fy_l);
	cx_r = opt("right", "cx", cx_l);
	cy_r = opt("right", "cy", cy_l);
	baseline_m = need("stereo", "baseline_m");
	const double w = need("stereo", "width"), h = need("stereo", "height");
	if (!(fx_l > 0) || !(fy_l > 0) || !(fx_r > 0) || !(fy_r > 0))
		throw DatasetError("[left]/[right] fx, fy: focal lengths must be > 0 (pixels)");
	if (!(baseline_m > 0))
		throw DatasetError("[stereo] baseline_m: must be > 0 (metres, right camera along +x)");
	if (!(w >= 1) || !(h >= 1) || w != std::floor(w) || h != std::floor(h))
		throw DatasetError("[stereo] width/height: must be positive integers (pixels)");
	width = uint32_t(w);
	height = uint32_t(h);
}

void TFolderCalib::dumpToTextStream(std::ostream& out) const
{
	out << "[left]  fx = " << fx_l << " fy = " << fy_l << " cx = " << cx_l << " cy = " << cy_l
		<< "  ; px\n"
		<< "[right] fx = " << fx_r << " fy = " << fy_r << " cx = " << cx_r << " cy = " << cy_r
		<< "  ; px\n"
		<< "[stereo] baseline_m = " << baseline_m << " ; m,  width = " << width
		<< " height = " << height << " ; px\n";
}

TFolderCalib TFolderCalib::FromFile(const std::string& iniPath)
{
	if (!fs::is_regular_file(iniPath)) throw DatasetError("'" + iniPath + "': no such calibration file");
	mrpt::config::CConfigFile cfg(iniPath);
	TFolderCalib c;
	try
	{
		c.loadFromConfigFile(cfg, "");
	}
	catch (const DatasetError& e)
	{
		throw DatasetError("'" + iniPath + "': " + e.what());
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
		for (size_t i = 1; i < times.size(); i++)
			if (!(times[i] > times[i - 1]))
				throw DatasetError(
					"'" + timesFile + "': timestamp #" + std::to_string(i) + " (" + std::to_string(times[i]) +
					" s) is not after #" + std::to_string(i - 1) + " (" + std::to_string(times[i - 1]) +
					" s): timestamps must increase with the (sorted) image names");
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

	auto camera = [&](double fx, double fy, double cx, double cy) {
		mrpt::img::TCamera c;
		c.ncols = calib.width;
		c.nrows = calib.height;
		c.setIntrinsicParamsFromValues(fx, fy, cx, cy);
		c.dist.fill(0);
		return c;
	};
	detail::StereoSink sink(outRawlog, options, *this);
	sink.addInput(leftDir, "left image folder");
	sink.addInput(rightDir, "right image folder");
	sink.addInput(calibIni, "calibration");
	if (!timesFile.empty()) sink.addInput(timesFile, "timestamps file");
	sink.setCalibration(
		camera(calib.fx_l, calib.fy_l, calib.cx_l, calib.cy_l),
		camera(calib.fx_r, calib.fy_r, calib.cx_r, calib.cy_r), calib.baseline_m);
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
