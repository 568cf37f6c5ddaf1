/* ShadyLoc — Middlebury 2014 scene -> rawlog. */
#include <shadyloc/datasets/Middlebury.h>

#include "Detail.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace shadyloc::datasets
{
namespace
{
std::string trim(const std::string& s)
{
	const auto a = s.find_first_not_of(" \t\r\n");
	if (a == std::string::npos) return "";
	return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

/** "[ a b c ; d e f ; g h i ]" -> 3x3. */
mrpt::math::CMatrixDouble33 parseMatrix(const std::string& text, const std::string& where)
{
	std::string t = trim(text);
	if (t.size() < 2 || t.front() != '[' || t.back() != ']')
		throw DatasetError(where + ": expected '[a b c; d e f; g h i]', got '" + text + "'");
	t = t.substr(1, t.size() - 2);
	for (auto& ch : t)
		if (ch == ';') ch = ' ';
	std::istringstream ss(t);
	std::vector<double> v;
	std::string tok;
	while (ss >> tok) v.push_back(detail::parseDouble(tok, where));
	if (v.size() != 9)
		throw DatasetError(where + ": " + std::to_string(v.size()) + " values, 9 expected (3x3)");
	mrpt::math::CMatrixDouble33 M;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) M(r, c) = v[r * 3 + c];
	if (!(M(0, 0) > 0) || !(M(1, 1) > 0) || M(2, 2) != 1 || M(1, 0) != 0 || M(2, 0) != 0 || M(2, 1) != 0)
		throw DatasetError(where + ": not a camera matrix [f 0 cx; 0 f cy; 0 0 1]");
	return M;
}
}  // namespace

TMiddleburyCalib TMiddleburyCalib::FromFile(const std::string& path)
{
	if (!fs::is_regular_file(path)) throw DatasetError("'" + path + "': no such calibration file");
	std::ifstream f(path);
	if (!f) throw DatasetError("'" + path + "': cannot open calibration file");
	std::map<std::string, std::string> kv;
	std::string line;
	while (std::getline(f, line))
	{
		const auto eq = line.find('=');
		if (eq == std::string::npos) continue;
		kv[trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
	}
	auto need = [&](const std::string& key) -> const std::string& {
		auto it = kv.find(key);
		if (it == kv.end() || it->second.empty())
			throw DatasetError("'" + path + "': missing key '" + key + "='");
		return it->second;
	};
	auto num = [&](const std::string& key) {
		return detail::parseDouble(need(key), "'" + path + "': " + key);
	};
	TMiddleburyCalib c;
	c.cam0 = parseMatrix(need("cam0"), "'" + path + "': cam0");
	c.cam1 = parseMatrix(need("cam1"), "'" + path + "': cam1");
	c.doffs = num("doffs");
	c.baseline_mm = num("baseline");
	const double w = num("width"), h = num("height");
	if (!(w >= 1) || !(h >= 1) || w != std::floor(w) || h != std::floor(h))
		throw DatasetError("'" + path + "': width/height must be positive integers");
	c.width = uint32_t(w);
	c.height = uint32_t(h);
	if (!(c.baseline_mm > 0)) throw DatasetError("'" + path + "': baseline must be > 0 (mm)");
	if (kv.count("ndisp")) c.ndisp = int(num("ndisp"));
	return c;
}

MiddleburyImporter::MiddleburyImporter() : mrpt::system::COutputLogger("shadyloc.import.middlebury")
{
}

TImportResult MiddleburyImporter::run(const std::string& sceneDir, const std::string& outRawlog)
{
	if (!fs::is_directory(sceneDir))
		throw DatasetError("'" + sceneDir + "': no such Middlebury scene directory");
	const std::string calibPath = (fs::path(sceneDir) / "calib.txt").string();
	const auto calib = TMiddleburyCalib::FromFile(calibPath);
	// doffs is by definition cx1 - cx0; a file disagreeing with itself is worth a word.
	if (std::abs(calib.cam1(0, 2) - calib.cam0(0, 2) - calib.doffs) > 1e-3)
		MRPT_LOG_WARN_FMT(
			"'%s': doffs = %g but cx1 - cx0 = %g: keeping cam0 and cam1 as written", calibPath.c_str(),
			calib.doffs, calib.cam1(0, 2) - calib.cam0(0, 2));

	const std::string pathL = (fs::path(sceneDir) / leftImage).string();
	const std::string pathR = (fs::path(sceneDir) / rightImage).string();
	const cv::Mat L = detail::readImage(pathL, "frame 0 left");
	const cv::Mat R = detail::readImage(pathR, "frame 0 right");
	for (auto [m, p] : {std::pair{&L, &pathL}, std::pair{&R, &pathR}})
		if (uint32_t(m->cols) != calib.width || uint32_t(m->rows) != calib.height)
			throw DatasetError(
				"'" + *p + "' is " + std::to_string(m->cols) + "x" + std::to_string(m->rows) + " but '" +
				calibPath + "' says " + std::to_string(calib.width) + "x" + std::to_string(calib.height));

	auto camera = [&](const mrpt::math::CMatrixDouble33& K) {
		mrpt::img::TCamera c;
		c.ncols = calib.width;
		c.nrows = calib.height;
		c.setIntrinsicParamsFromValues(K(0, 0), K(1, 1), K(0, 2), K(1, 2));
		c.dist.fill(0);
		return c;
	};
	MRPT_LOG_INFO_FMT(
		"Middlebury scene '%s': %ux%u, f = %g px, baseline %g mm, doffs %g px", sceneDir.c_str(),
		calib.width, calib.height, calib.cam0(0, 0), calib.baseline_mm, calib.doffs);
	detail::StereoSink sink(outRawlog, options, *this);
	sink.addInput(sceneDir, "scene folder");
	sink.addInput(calibPath, "calibration");
	sink.setCalibration(camera(calib.cam0), camera(calib.cam1), calib.baseline_mm / 1000.0);
	sink.add(L, R, timestamp, "frame 0 ('" + pathL + "')");
	return sink.commit();
}

}  // namespace shadyloc::datasets
