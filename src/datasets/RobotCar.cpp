/* ShadyLoc — Oxford RobotCar traversal -> rawlog (formats: RobotCar.h). */
#include <shadyloc/datasets/RobotCar.h>

#include "Detail.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace shadyloc::datasets
{
namespace
{
// Longest text line accepted: the SDK's lines are < 300 characters; a binary
// file given by mistake must fail, not be read whole into one string.
constexpr size_t kMaxLine = 4096;

/** getline that refuses lines longer than kMaxLine (error naming file:line).
 * With `whole`, a last line without its newline is refused too: a download
 * cut there can end in a shortened number that still parses. */
bool readLine(std::istream& in, std::string& line, const std::string& where, bool whole = false)
{
	line.clear();
	for (int c; (c = in.get()) != EOF;)
	{
		if (c == '\n') return true;
		if (line.size() >= kMaxLine)
			throw DatasetError(where + ": line longer than " + std::to_string(kMaxLine) + " characters (not a text file?)");
		line += static_cast<char>(c);
	}
	if (whole && !line.empty())
		throw DatasetError(where + ": the last line does not end with a newline (truncated file?)");
	return !line.empty();
}

std::string at(const std::string& path, size_t lineNo)
{
	return "'" + path + "':" + std::to_string(lineNo);
}

/** Whole-token integer (timestamps are microseconds: exact as int64). */
int64_t parseInt64(const std::string& token, const std::string& where)
{
	const char* s = token.c_str();
	char* end = nullptr;
	errno = 0;
	const long long v = std::strtoll(s, &end, 10);
	if (end == s || *end != '\0' || errno == ERANGE)
		throw DatasetError(where + ": '" + token + "' is not an integer timestamp (microseconds)");
	return v;
}

/** Splits on `sep` (a CSV row) or, with sep == 0, on white space. */
std::vector<std::string> split(const std::string& line, char sep)
{
	std::vector<std::string> out;
	if (sep == 0)
	{
		std::istringstream ss(line);
		for (std::string t; ss >> t;) out.push_back(t);
		return out;
	}
	std::string cur;
	for (char c : line)
		if (c == sep) out.push_back(cur), cur.clear();
		else if (c != '\r') cur += c;
	out.push_back(cur);
	return out;
}

std::ifstream openText(const std::string& path, const std::string& what)
{
	if (!fs::is_regular_file(path)) throw DatasetError("'" + path + "': no such " + what);
	std::ifstream f(path, std::ios::binary);
	if (!f) throw DatasetError("'" + path + "': cannot open " + what);
	return f;
}

/** Non-empty lines of a small text file as numbers, each line `where`-named. */
std::vector<std::vector<double>> readNumberLines(const std::string& path, const std::string& what)
{
	auto f = openText(path, what);
	std::vector<std::vector<double>> rows;
	std::string line;
	for (size_t n = 1; readLine(f, line, at(path, n)); n++)
	{
		const auto tok = split(line, 0);
		if (tok.empty()) continue;
		std::vector<double> v;
		for (const auto& t : tok) v.push_back(detail::parseDouble(t, at(path, n)));
		rows.push_back(v);
		if (rows.size() > 16) throw DatasetError(at(path, n) + ": too many lines for a " + what);
	}
	return rows;
}

/** An SE(3) matrix from 4 rows of 4; its rotation must be orthonormal. */
Eigen::Isometry3d isometryFromRows(const std::vector<std::vector<double>>& rows, const std::string& where)
{
	Eigen::Matrix4d M;
	for (int r = 0; r < 4; r++)
		for (int c = 0; c < 4; c++) M(r, c) = rows[r][c];
	const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
	if ((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-4 || std::abs(R.determinant() - 1) > 1e-4 ||
		(M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9)
		throw DatasetError(where + ": G_camera_image (lines 2-5) is not a rigid transform (rotation, last row 0 0 0 1)");
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();	// printed digits: nearest rotation
	T.translation() = M.topRightCorner<3, 1>();
	return T;
}
}  // namespace

// ---------------------------------------------------------------- camera models
TRobotCarCameraModel TRobotCarCameraModel::FromFile(const std::string& modelsDir, const std::string& name)
{
	const std::string path = (fs::path(modelsDir) / (name + ".txt")).string();
	const auto rows = readNumberLines(path, "camera model (the SDK's models/" + name + ".txt)");
	if (rows.size() != 5)
		throw DatasetError("'" + path + "': " + std::to_string(rows.size()) + " lines of numbers, 5 expected (fx fy cx cy, then 4x4 G_camera_image)");
	for (size_t r = 0; r < 5; r++)
		if (rows[r].size() != 4)
			throw DatasetError("'" + path + "': line " + std::to_string(r + 1) + " has " + std::to_string(rows[r].size()) + " numbers, 4 expected");
	TRobotCarCameraModel m;
	m.name = name;
	m.fx = rows[0][0], m.fy = rows[0][1], m.cx = rows[0][2], m.cy = rows[0][3];
	if (!(m.fx > 0) || !(m.fy > 0)) throw DatasetError("'" + path + "': focal lengths must be > 0 (line 1: fx fy cx cy)");
	m.G_camera_image = isometryFromRows({rows.begin() + 1, rows.end()}, "'" + path + "'");
	return m;
}

void TRobotCarCameraModel::readLut(const std::string& modelsDir, int width, int height)
{
	const std::string path = (fs::path(modelsDir) / (name + "_distortion_lut.bin")).string();
	if (!fs::is_regular_file(path)) throw DatasetError("'" + path + "': no such look-up table (the SDK's models/)");
	const size_t n = size_t(width) * size_t(height);
	// Size checked before reading: the file's length is the only header it has.
	const auto bytes = fs::file_size(path);
	if (bytes != 2 * n * sizeof(double))
		throw DatasetError(
			"'" + path + "': " + std::to_string(bytes) + " bytes, expected " + std::to_string(2 * n * sizeof(double)) +
			" (2 x " + std::to_string(width) + " x " + std::to_string(height) + " float64: the images' size)");
	std::vector<double> lut(2 * n);
	std::ifstream f(path, std::ios::binary);
	if (!f.read(reinterpret_cast<char*>(lut.data()), std::streamsize(bytes)))
		throw DatasetError("'" + path + "': cannot read the look-up table");
	mapX.create(height, width, CV_32FC1);
	mapY.create(height, width, CV_32FC1);
	for (size_t i = 0; i < n; i++)
	{
		if (!std::isfinite(lut[i]) || !std::isfinite(lut[n + i]))
			throw DatasetError("'" + path + "': entry " + std::to_string(i) + " is not a finite number");
		// All u (column) first, then all v (row); pixels row-major.
		mapX.at<float>(int(i / width), int(i % width)) = float(lut[i]);
		mapY.at<float>(int(i / width), int(i % width)) = float(lut[n + i]);
	}
}

TRobotCarCameraModel TRobotCarCameraModel::halved() const
{
	if (mapX.empty() || mapX.cols % 2 || mapX.rows % 2)
		throw DatasetError(
			"'" + name + "': half-resolution demosaicing needs an even image size (Bayer cells of 2x2), got " +
			std::to_string(mapX.cols) + "x" + std::to_string(mapX.rows));
	TRobotCarCameraModel h = *this;
	// Pixel centres: full-resolution 2x + 0.5 is half-resolution x.
	h.fx = fx / 2, h.fy = fy / 2, h.cx = (cx - 0.5) / 2, h.cy = (cy - 0.5) / 2;
	// INTER_AREA at exactly half size is the mean of each 2x2 block: the
	// table's value at the block's centre, to first order.
	cv::resize(mapX, h.mapX, cv::Size(mapX.cols / 2, mapX.rows / 2), 0, 0, cv::INTER_AREA);
	cv::resize(mapY, h.mapY, cv::Size(mapY.cols / 2, mapY.rows / 2), 0, 0, cv::INTER_AREA);
	h.mapX = (h.mapX - 0.5) * 0.5;
	h.mapY = (h.mapY - 0.5) * 0.5;
	return h;
}

namespace
{
/** One BGR pixel per GBRG cell (row 0: G B, row 1: R G), green the mean of
 * the two: every value measured, none interpolated. Blue sits a quarter
 * output pixel up-right of the cell centre and red down-left. */
cv::Mat superpixels(const cv::Mat& raw)
{
	cv::Mat out(raw.rows / 2, raw.cols / 2, CV_8UC3);
	for (int r = 0; r < out.rows; r++)
	{
		const uint8_t* a = raw.ptr<uint8_t>(2 * r);
		const uint8_t* b = raw.ptr<uint8_t>(2 * r + 1);
		auto* o = out.ptr<cv::Vec3b>(r);
		for (int c = 0; c < out.cols; c++)
			o[c] = cv::Vec3b(a[2 * c + 1], uint8_t((a[2 * c] + b[2 * c + 1] + 1) / 2), b[2 * c]);
	}
	return out;
}
}  // namespace

cv::Mat TRobotCarCameraModel::rectify(const cv::Mat& raw, const std::string& what, TDemosaic method) const
{
	if (raw.channels() != 1)
		throw DatasetError(what + ": " + std::to_string(raw.channels()) + " channels, a raw Bayer mosaic has 1 (already demosaiced?)");
	const int k = method == TDemosaic::HalfResolution ? 2 : 1;	// raw pixels per output pixel
	if (raw.cols != k * mapX.cols || raw.rows != k * mapX.rows)
		throw DatasetError(
			what + ": image is " + std::to_string(raw.cols) + "x" + std::to_string(raw.rows) + ", the look-up table of '" +
			name + "' is for " + std::to_string(k * mapX.cols) + "x" + std::to_string(k * mapX.rows));
	// The stereo camera's pattern is GBRG (row 0: G B, row 1: R G); OpenCV
	// names Bayer codes by the second row's 2nd and 3rd pixels, so GBRG is
	// its BayerGR (alias BayerGBRG). Bilinear is what the SDK does.
	cv::Mat bgr, out;
	if (method == TDemosaic::HalfResolution) bgr = superpixels(raw);
	else cv::cvtColor(raw, bgr, method == TDemosaic::EdgeAware ? cv::COLOR_BayerGBRG2BGR_EA : cv::COLOR_BayerGBRG2BGR);
	// The SDK undistorts after demosaicing, bilinear, zero outside the image.
	cv::remap(bgr, out, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
	return out;
}

// ---------------------------------------------------------------- extrinsics
Eigen::Isometry3d robotcarTransform(const double v[6])
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
				  Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
					 .toRotationMatrix();
	T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
	return T;
}

Eigen::Isometry3d readRobotCarExtrinsics(const std::string& path)
{
	const auto rows = readNumberLines(path, "extrinsics file (the SDK's extrinsics/)");
	if (rows.size() != 1 || rows[0].size() != 6)
		throw DatasetError("'" + path + "': expected one line 'x y z roll pitch yaw' (metres, radians)");
	return robotcarTransform(rows[0].data());
}

// ---------------------------------------------------------------- INS
std::vector<TRobotCarInsPose> readRobotCarIns(const std::string& path)
{
	auto f = openText(path, "INS file (gps/ins.csv)");
	std::string line;
	if (!readLine(f, line, at(path, 1))) throw DatasetError("'" + path + "': empty (a header line and INS rows expected)");
	const auto header = split(line, ',');
	static const char* cols[] = {"timestamp", "northing", "easting", "down", "roll", "pitch", "yaw"};
	size_t idx[7];
	for (int k = 0; k < 7; k++)
	{
		auto it = std::find(header.begin(), header.end(), cols[k]);
		if (it == header.end()) throw DatasetError(at(path, 1) + ": the header has no '" + cols[k] + "' column");
		idx[k] = size_t(it - header.begin());
	}
	std::vector<TRobotCarInsPose> out;
	for (size_t n = 2; readLine(f, line, at(path, n), true); n++)
	{
		if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
		const auto row = split(line, ',');
		// A row cut short (a truncated download) must not shift the columns.
		if (row.size() != header.size())
			throw DatasetError(
				at(path, n) + ": " + std::to_string(row.size()) + " fields, the header has " + std::to_string(header.size()) +
				" (truncated file?)");
		TRobotCarInsPose p;
		p.t_us = parseInt64(row[idx[0]], at(path, n) + " (timestamp)");
		double v[6];
		for (int k = 0; k < 6; k++) v[k] = detail::parseDouble(row[idx[k + 1]], at(path, n) + " (" + cols[k + 1] + ")");
		p.T_world_ins = robotcarTransform(v);
		if (!out.empty() && p.t_us <= out.back().t_us)
			throw DatasetError(at(path, n) + ": timestamp " + std::to_string(p.t_us) + " is not after the row before (" + std::to_string(out.back().t_us) + ")");
		out.push_back(p);
	}
	if (out.empty()) throw DatasetError("'" + path + "': no INS rows after the header");
	return out;
}

Eigen::Isometry3d interpolateRobotCarIns(
	const std::vector<TRobotCarInsPose>& ins, int64_t t, const std::string& where)
{
	auto hi = std::lower_bound(
		ins.begin(), ins.end(), t, [](const TRobotCarInsPose& p, int64_t v) { return p.t_us < v; });
	if (hi != ins.end() && hi->t_us == t) return hi->T_world_ins;
	if (hi == ins.begin() || hi == ins.end())
		throw DatasetError(
			where + ": no INS pose on both sides of t = " + std::to_string(t) + " us (INS rows span " +
			std::to_string(ins.front().t_us) + " .. " + std::to_string(ins.back().t_us) + ")");
	const auto lo = std::prev(hi);
	const double a = double(t - lo->t_us) / double(hi->t_us - lo->t_us);
	const Eigen::Quaterniond q0(lo->T_world_ins.linear()), q1(hi->T_world_ins.linear());
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = q0.slerp(a, q1).toRotationMatrix();
	T.translation() = (1 - a) * lo->T_world_ins.translation() + a * hi->T_world_ins.translation();
	return T;
}

// ---------------------------------------------------------------- import
namespace
{
struct TStereoStamp
{
	int64_t t_us;
	size_t line;
};

/** stereo.timestamps: "<t_us> <chunk>" lines; times must increase. */
std::vector<TStereoStamp> readStereoTimestamps(const std::string& path)
{
	auto f = openText(path, "timestamps file (stereo.timestamps)");
	std::vector<TStereoStamp> out;
	std::string line;
	for (size_t n = 1; readLine(f, line, at(path, n), true); n++)
	{
		const auto tok = split(line, 0);
		if (tok.empty()) continue;
		if (tok.size() > 2) throw DatasetError(at(path, n) + ": expected '<timestamp_us> <chunk>'");
		const int64_t t = parseInt64(tok[0], at(path, n));
		if (t <= 0) throw DatasetError(at(path, n) + ": timestamp " + tok[0] + " is not a Unix time in microseconds (> 0)");
		if (tok.size() == 2) parseInt64(tok[1], at(path, n) + " (chunk)");
		if (!out.empty() && t <= out.back().t_us)
			throw DatasetError(at(path, n) + ": timestamp " + tok[0] + " is not after the line before: timestamps must increase");
		out.push_back({t, n});
	}
	if (out.empty()) throw DatasetError("'" + path + "': no timestamps");
	return out;
}

std::string imagePath(const std::string& traversal, const char* side, int64_t t)
{
	return (fs::path(traversal) / "stereo" / side / (std::to_string(t) + ".png")).string();
}

/** The lens offsets of a rectified pair: right lens along +x of the left's image frame. */
double baselineOf(const TRobotCarCameraModel& L, const TRobotCarCameraModel& R, const std::string& modelsDir)
{
	const Eigen::Isometry3d T_lr = L.G_camera_image.inverse() * R.G_camera_image;
	const Eigen::Vector3d t = T_lr.translation();
	const double angle = Eigen::AngleAxisd(T_lr.linear()).angle();
	if (!(t.x() > 0) || std::abs(t.y()) > 1e-3 || std::abs(t.z()) > 1e-3 || angle > 1e-3)
		throw DatasetError(
			"'" + modelsDir + "': " + R.name + " is not a rectified partner of " + L.name +
			" (right lens must sit along +x of the left image frame, no rotation; got t = (" + std::to_string(t.x()) +
			", " + std::to_string(t.y()) + ", " + std::to_string(t.z()) + ") m, " + std::to_string(angle) + " rad)");
	if (std::abs(L.fx - R.fx) > 1e-6 * L.fx || std::abs(L.fy - R.fy) > 1e-6 * L.fy || std::abs(L.cy - R.cy) > 1e-3)
		throw DatasetError("'" + modelsDir + "': " + L.name + " and " + R.name + " differ in fx, fy or cy: not a rectified pair");
	return t.x();
}

/** T_world_left at each frame's time (formula in RobotCar.h). */
std::vector<Eigen::Isometry3d> groundTruthPoses(
	const std::vector<TStereoStamp>& frames, const std::string& insPath, const std::string& stampsPath,
	const std::string& extrinsicsDir, const TRobotCarCameraModel& left)
{
	if (extrinsicsDir.empty() || !fs::is_directory(extrinsicsDir))
		throw DatasetError(
			"'" + extrinsicsDir + "': no such extrinsics folder (the SDK's extrinsics/, stereo.txt and ins.txt: "
			"the ground truth needs them; or import without ground truth)");
	const auto G_stereo_vehicle = readRobotCarExtrinsics((fs::path(extrinsicsDir) / "stereo.txt").string());
	const auto G_vehicle_ins = readRobotCarExtrinsics((fs::path(extrinsicsDir) / "ins.txt").string());
	// The SDK maps INS coordinates into the stereo camera's base frame with
	// G_stereo_vehicle * G_vehicle_ins; the lens's image frame is G_camera_image.
	const Eigen::Isometry3d T_ins_left = (G_stereo_vehicle * G_vehicle_ins).inverse() * left.G_camera_image;
	const auto ins = readRobotCarIns(insPath);
	std::vector<Eigen::Isometry3d> out;
	for (size_t k = 0; k < frames.size(); k++)
		out.push_back(
			interpolateRobotCarIns(ins, frames[k].t_us, at(stampsPath, frames[k].line) + " (frame " + std::to_string(k) + ")") *
			T_ins_left);
	return out;
}

mrpt::img::TCamera cameraOf(const TRobotCarCameraModel& m, const cv::Rect& roi)
{
	mrpt::img::TCamera c;
	c.ncols = uint32_t(roi.width);
	c.nrows = uint32_t(roi.height);
	// A crop moves the principal point; the focal lengths stay.
	c.setIntrinsicParamsFromValues(m.fx, m.fy, m.cx - roi.x, m.cy - roi.y);
	c.dist.fill(0);	 // rectified
	return c;
}
}  // namespace

RobotCarImporter::RobotCarImporter() : mrpt::system::COutputLogger("shadyloc.import.robotcar") {}

TImportResult RobotCarImporter::run(const std::string& traversal, const std::string& outRawlog)
{
	if (!fs::is_directory(traversal)) throw DatasetError("'" + traversal + "': no such RobotCar traversal folder");
	if (modelsDir.empty() || !fs::is_directory(modelsDir))
		throw DatasetError("'" + modelsDir + "': no such camera models folder (the SDK's models/)");
	if (stride < 1) throw DatasetError("robotcar import: the frame stride must be >= 1");

	// Everything that can be checked without reading images, first.
	auto L = TRobotCarCameraModel::FromFile(modelsDir, "stereo_wide_left");
	auto R = TRobotCarCameraModel::FromFile(modelsDir, "stereo_wide_right");
	const double baseline = baselineOf(L, R, modelsDir);

	const std::string stampsPath = (fs::path(traversal) / "stereo.timestamps").string();
	const auto stamps = readStereoTimestamps(stampsPath);
	if (firstFrame >= stamps.size())
		throw DatasetError(
			"first frame " + std::to_string(firstFrame) + " is past the end of '" + stampsPath + "' (" +
			std::to_string(stamps.size()) + " frames)");
	std::vector<TStereoStamp> frames;
	for (size_t i = firstFrame; i < stamps.size(); i += stride)
	{
		if (options.maxFrames > 0 && frames.size() == options.maxFrames) break;
		frames.push_back(stamps[i]);
	}
	// A timestamp without its two images is a broken download: refuse it.
	for (const auto& s : frames)
		for (const char* side : {"left", "right"})
			if (!fs::is_regular_file(imagePath(traversal, side, s.t_us)))
				throw DatasetError(
					at(stampsPath, s.line) + ": timestamp " + std::to_string(s.t_us) + " has no " + side + " image '" +
					imagePath(traversal, side, s.t_us) + "'");

	std::vector<Eigen::Isometry3d> gt;
	const std::string insPath = (fs::path(traversal) / "gps" / "ins.csv").string();
	if (groundTruth) gt = groundTruthPoses(frames, insPath, stampsPath, extrinsicsDir, L);
	for (auto& T : gt) T.translation() -= groundTruthOrigin;

	// The images give the look-up tables' size.
	const auto frameName = [&](size_t k) { return "frame " + std::to_string(k) + " (" + std::to_string(frames[k].t_us) + ")"; };
	const cv::Mat first = detail::readImage(imagePath(traversal, "left", frames[0].t_us), frameName(0) + " left");
	L.readLut(modelsDir, first.cols, first.rows);
	R.readLut(modelsDir, first.cols, first.rows);
	if (demosaic == TDemosaic::HalfResolution) L = L.halved(), R = R.halved();
	const cv::Rect full(0, 0, L.mapX.cols, L.mapX.rows);  // the output images
	const cv::Rect roi = crop.empty() ? full : crop;
	if ((roi & full) != roi)
		throw DatasetError(
			"crop " + std::to_string(roi.width) + "x" + std::to_string(roi.height) + "+" + std::to_string(roi.x) + "+" +
			std::to_string(roi.y) + " is not inside the " + std::to_string(full.width) + "x" + std::to_string(full.height) + " output images");

	MRPT_LOG_INFO_STREAM(
		"RobotCar traversal '" << traversal << "': " << stamps.size() << " frames, importing " << frames.size()
							   << " (from #" << firstFrame << ", every " << stride << "), " << roi.width << "x" << roi.height
							   << ", baseline " << baseline << " m, demosaicing "
							   << (demosaic == TDemosaic::Bilinear ? "bilinear" : demosaic == TDemosaic::EdgeAware ? "edge-aware" : "half")
							   << ", ground truth: " << (groundTruth ? insPath : "none"));

	detail::StereoSink sink(outRawlog, options, *this);
	sink.addInput(traversal, "RobotCar traversal folder");
	sink.addInput(modelsDir, "camera models folder");
	if (groundTruth) sink.addInput(extrinsicsDir, "extrinsics folder");
	sink.setCalibration(cameraOf(L, roi), cameraOf(R, roi), baseline);
	for (size_t k = 0; k < frames.size(); k++)
	{
		const int64_t t = frames[k].t_us;
		const std::string frame = frameName(k);
		const cv::Mat rawL = k == 0 ? first : detail::readImage(imagePath(traversal, "left", t), frame + " left");
		const cv::Mat rawR = detail::readImage(imagePath(traversal, "right", t), frame + " right");
		const double seconds = double(t) * 1e-6;
		sink.add(L.rectify(rawL, frame + " left", demosaic)(roi), R.rectify(rawR, frame + " right", demosaic)(roi), seconds, frame);
		if (groundTruth)
			sink.groundTruth.push_back({mrpt::Clock::toDouble(detail::timestampFromSeconds(seconds)), gt[k]});
	}
	auto res = sink.commit();
	MRPT_LOG_INFO_FMT(
		"Wrote %zu frames to '%s' in %.2f s%s", res.frames, outRawlog.c_str(), res.seconds,
		res.groundTruthPath.empty() ? "" : (", ground truth '" + res.groundTruthPath + "'").c_str());
	return res;
}

}  // namespace shadyloc::datasets
