/* ShadyLoc — KITTI odometry layout <-> rawlog. */
#include <shadyloc/datasets/Folder.h>
#include <shadyloc/datasets/Kitti.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/io/OutputTransaction.h>

#include "Detail.h"

#include <shadyloc/core/Options.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace shadyloc::datasets
{
// ---------------------------------------------------------------- calib.txt
TKittiCalib TKittiCalib::FromFile(const std::string& path)
{
	if (!fs::is_regular_file(path)) throw DatasetError("'" + path + "': no such calibration file");
	std::ifstream f(path);
	if (!f) throw DatasetError("'" + path + "': cannot open calibration file");
	TKittiCalib c;
	std::string line;
	for (size_t n = 1; std::getline(f, line); n++)
	{
		const auto colon = line.find(':');
		if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
		if (colon == std::string::npos)
			throw DatasetError("'" + path + "':" + std::to_string(n) + ": expected 'Name: values'");
		std::string name = line.substr(0, colon);
		name.erase(0, name.find_first_not_of(" \t"));
		name.erase(name.find_last_not_of(" \t") + 1);
		std::istringstream ss(line.substr(colon + 1));
		std::vector<double> v;
		std::string tok;
		while (ss >> tok)
			v.push_back(detail::parseDouble(tok, "'" + path + "':" + std::to_string(n) + " (" + name + ")"));
		if (v.size() != 12)
		{
			// Other keys (KITTI raw's S_xx, R_xx, ...) are not 3x4: skip them,
			// but a projection matrix must be complete.
			if (name.size() == 2 && name[0] == 'P')
				throw DatasetError(
					"'" + path + "':" + std::to_string(n) + ": " + name + " has " +
					std::to_string(v.size()) + " values, 12 expected (3x4 row-major)");
			continue;
		}
		TMatrix34 M;
		for (int r = 0; r < 3; r++)
			for (int k = 0; k < 4; k++) M(r, k) = v[r * 4 + k];
		c.P[name] = M;
	}
	return c;
}

const TMatrix34& TKittiCalib::get(const std::string& name, const std::string& path) const
{
	auto it = P.find(name);
	if (it == P.end())
		throw DatasetError(
			"'" + path + "': no '" + name +
			":' line (the colour stereo pair needs P2 and P3, 3x4 row-major)");
	return it->second;
}

mrpt::img::TCamera cameraFromProjection(const TMatrix34& P, uint32_t ncols, uint32_t nrows)
{
	mrpt::img::TCamera c;
	c.ncols = ncols;
	c.nrows = nrows;
	c.setIntrinsicParamsFromValues(P(0, 0), P(1, 1), P(0, 2), P(1, 2));
	c.dist.fill(0);	 // rectified images
	return c;
}

mrpt::math::TPoint3D translationFromProjection(const TMatrix34& P)
{
	// P[:,3] = K t with K upper triangular (K(2,2) = 1): back-substitute.
	const double tz = P(2, 3) / P(2, 2);
	const double ty = (P(1, 3) - P(1, 2) * tz) / P(1, 1);
	const double tx = (P(0, 3) - P(0, 1) * ty - P(0, 2) * tz) / P(0, 0);
	return {tx, ty, tz};
}

TMatrix34 projectionFromCamera(const mrpt::img::TCamera& cam, const mrpt::math::TPoint3D& t)
{
	TMatrix34 P;
	P.setZero();
	P(0, 0) = cam.fx();
	P(0, 2) = cam.cx();
	P(1, 1) = cam.fy();
	P(1, 2) = cam.cy();
	P(2, 2) = 1;
	P(0, 3) = cam.fx() * t.x + cam.cx() * t.z;
	P(1, 3) = cam.fy() * t.y + cam.cy() * t.z;
	P(2, 3) = t.z;
	return P;
}

std::string kittiSequenceDir(const std::string& root, const std::string& sequence)
{
	return (fs::path(root) / "sequences" / sequence).string();
}

namespace
{
void checkCamera(const TMatrix34& P, const std::string& name, const std::string& path)
{
	if (!(P(0, 0) > 0) || !(P(1, 1) > 0) || std::abs(P(2, 2) - 1.0) > 1e-9 || P(1, 0) != 0 ||
		P(2, 0) != 0 || P(2, 1) != 0)
		throw DatasetError(
			"'" + path + "': " + name +
			" is not a rectified projection K[I|t] (need fx, fy > 0, last row 0 0 1 tz)");
}

/** A 3x4 KITTI pose line -> CPose3D, rotation projected onto SO(3). */
mrpt::poses::CPose3D poseFrom34(const double* v, const std::string& where)
{
	Eigen::Matrix3d R;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) R(r, c) = v[r * 4 + c];
	if (std::abs(R.determinant() - 1.0) > 1e-2 ||
		(R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-2)
		throw DatasetError(where + ": the 3x3 part is not a rotation matrix");
	// KITTI prints 7 significant digits, so R is orthonormal to ~1e-7 only: the
	// quaternion is the nearest rotation.
	Eigen::Quaterniond q(R);
	q.normalize();
	return mrpt::poses::CPose3D(
		mrpt::math::CQuaternionDouble(q.w(), q.x(), q.y(), q.z()), v[3], v[7], v[11]);
}

std::vector<mrpt::poses::CPose3D> readKittiPoses(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw DatasetError("'" + path + "': cannot open poses file");
	std::vector<mrpt::poses::CPose3D> out;
	std::string line;
	for (size_t n = 1; std::getline(f, line); n++)
	{
		std::istringstream ss(line);
		std::vector<double> v;
		std::string tok;
		const std::string where = "'" + path + "':" + std::to_string(n);
		while (ss >> tok) v.push_back(detail::parseDouble(tok, where));
		if (v.empty()) continue;
		if (v.size() != 12)
			throw DatasetError(
				where + ": " + std::to_string(v.size()) + " values, 12 expected (3x4 row-major pose)");
		out.push_back(poseFrom34(v.data(), where));
	}
	return out;
}

std::string poseTo34(const Eigen::Isometry3d& T)
{
	const Eigen::Matrix3d R = T.linear();
	const Eigen::Vector3d t = T.translation();
	char buf[512];
	std::snprintf(
		buf, sizeof(buf), "%.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e", R(0, 0),
		R(0, 1), R(0, 2), t.x(), R(1, 0), R(1, 1), R(1, 2), t.y(), R(2, 0), R(2, 1), R(2, 2), t.z());
	return buf;
}

std::string matrixLine(const std::string& name, const TMatrix34& P)
{
	std::string s = name + ":";
	char buf[32];
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 4; c++)
		{
			std::snprintf(buf, sizeof(buf), " %.12e", P(r, c));
			s += buf;
		}
	return s;
}
}  // namespace

// ---------------------------------------------------------------- import
KittiImporter::KittiImporter() : mrpt::system::COutputLogger("shadyloc.import.kitti") {}

TImportResult KittiImporter::run(
	const std::string& root, const std::string& sequence, const std::string& outRawlog)
{
	if (!fs::is_directory(root)) throw DatasetError("'" + root + "': no such KITTI root directory");
	const std::string seqDir = kittiSequenceDir(root, sequence);
	if (!fs::is_directory(seqDir))
		throw DatasetError("'" + seqDir + "': no such sequence directory (sequence '" + sequence + "')");

	// Everything that can be checked without reading images, first.
	const std::string calibPath = (fs::path(seqDir) / "calib.txt").string();
	const auto calib = TKittiCalib::FromFile(calibPath);
	const TMatrix34& P2 = calib.get("P2", calibPath);
	const TMatrix34& P3 = calib.get("P3", calibPath);
	checkCamera(P2, "P2", calibPath);
	checkCamera(P3, "P3", calibPath);

	const std::string dirL = (fs::path(seqDir) / "image_2").string();
	const std::string dirR = (fs::path(seqDir) / "image_3").string();
	const auto filesL = listImages(dirL), filesR = listImages(dirR);
	if (filesL.empty()) throw DatasetError("'" + dirL + "': no images");
	if (filesL.size() != filesR.size())
		throw DatasetError(
			"mismatched image counts: '" + dirL + "' has " + std::to_string(filesL.size()) +
			" images, '" + dirR + "' has " + std::to_string(filesR.size()));
	for (size_t i = 0; i < filesL.size(); i++)
		if (fs::path(filesL[i]).filename() != fs::path(filesR[i]).filename())
			throw DatasetError(
				"frame " + std::to_string(i) + ": left image '" + filesL[i] +
				"' has no right partner of the same name (found '" + filesR[i] + "')");

	const std::string timesPath = (fs::path(seqDir) / "times.txt").string();
	if (!fs::is_regular_file(timesPath)) throw DatasetError("'" + timesPath + "': no such file");
	const auto times = detail::readTimes(timesPath);
	if (times.size() != filesL.size())
		throw DatasetError(
			"'" + timesPath + "' has " + std::to_string(times.size()) + " timestamps for " +
			std::to_string(filesL.size()) + " stereo frames");
	detail::checkTimesIncrease(times, timesPath, "the frame numbers");

	const std::string posesPath = (fs::path(root) / "poses" / (sequence + ".txt")).string();
	std::vector<mrpt::poses::CPose3D> T_world_cam0;
	if (fs::exists(posesPath))
	{
		T_world_cam0 = readKittiPoses(posesPath);
		if (T_world_cam0.size() != filesL.size())
			throw DatasetError(
				"'" + posesPath + "' has " + std::to_string(T_world_cam0.size()) + " poses for " +
				std::to_string(filesL.size()) + " stereo frames");
	}

	size_t n = filesL.size();
	if (options.maxFrames > 0) n = std::min(n, options.maxFrames);

	// Geometry (see Kitti.h): camera i sits at -t_i in cam0's frame.
	const auto t2 = translationFromProjection(P2), t3 = translationFromProjection(P3);
	const double baseline = t2.x - t3.x;
	if (!(baseline > 0))
		throw DatasetError(
			"'" + calibPath + "': P3 is not to the right of P2 (baseline " + std::to_string(baseline) +
			" m): are P2/P3 swapped?");
	const mrpt::poses::CPose3D T_cam0_left(-t2.x, -t2.y, -t2.z, 0, 0, 0);

	MRPT_LOG_INFO_STREAM(
		"KITTI sequence '" << seqDir << "': " << filesL.size() << " frames, importing " << n
						   << ", baseline " << baseline << " m, ground truth: "
						   << (T_world_cam0.empty() ? "none" : posesPath));

	const cv::Mat first = detail::readImage(filesL[0], "frame 0 (left)");
	detail::StereoSink sink(outRawlog, options, *this);
	sink.addInput(seqDir, "KITTI sequence folder");
	if (fs::exists(posesPath)) sink.addInput(posesPath, "KITTI poses");
	sink.setCalibration(
		cameraFromProjection(P2, first.cols, first.rows), cameraFromProjection(P3, first.cols, first.rows),
		baseline);
	for (size_t i = 0; i < n; i++)
	{
		const std::string frame =
			"frame " + std::to_string(i) + " ('" + fs::path(filesL[i]).filename().string() + "')";
		const cv::Mat L = i == 0 ? first : detail::readImage(filesL[i], frame + " left");
		const cv::Mat R = detail::readImage(filesR[i], frame + " right");
		sink.add(L, R, times[i], frame);
		if (!T_world_cam0.empty())
			sink.groundTruth.push_back(
				{mrpt::Clock::toDouble(detail::timestampFromSeconds(times[i])),
				 io::toIsometry(T_world_cam0[i] + T_cam0_left)});
	}
	auto res = sink.commit();
	MRPT_LOG_INFO_FMT(
		"Wrote %zu frames to '%s' in %.2f s%s", res.frames, outRawlog.c_str(), res.seconds,
		res.groundTruthPath.empty() ? "" : (", ground truth '" + res.groundTruthPath + "'").c_str());
	return res;
}

// ---------------------------------------------------------------- export
void KittiExporter::TOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	v.renamed(
		{{"sensorLabel", "sensor_label"},
		 {"groundTruthTum", "ground_truth_tum"},
		 {"gtTimeTolerance", "gt_time_tolerance_s"},
		 {"absoluteTimes", "absolute_times"},
		 {"progressEvery", "progress_every"}});
	v("sequence", sequence, "", Range::any(), "NN");
	v("sensor_label", sensorLabel, "", Range::any(), "which stereo observations to export");
	v("ground_truth_tum", groundTruthTum, "", Range::any(), "TUM file for poses/NN.txt, empty: none");
	v("gt_time_tolerance_s", gtTimeTolerance, "s", Range::atLeast(0), "max |t_frame - t_gt| to pair a pose");
	v("absolute_times", absoluteTimes, "", Range::any(), "times.txt: absolute instead of since frame 0");
	v("progress_every", progressEvery, "", Range::any(), "log progress every this many frames, 0: never");
}

void KittiExporter::TOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::loadKeys(*this, c, s);
}

void KittiExporter::TOptions::dumpToTextStream(std::ostream& out) const { core::dumpKeys(*this, out); }

void KittiExporter::TOptions::validate() const { core::checkKeys(*this); }

KittiExporter::KittiExporter() : mrpt::system::COutputLogger("shadyloc.export.kitti") {}

namespace
{
/** Removes the directories we created (if left empty) unless dismissed; the
 * output transaction removes the staged sequence. */
struct StagingGuard
{
	std::vector<fs::path> created;	//!< innermost last
	bool dismissed = false;
	~StagingGuard()
	{
		if (dismissed) return;
		std::error_code ec;
		for (auto it = created.rbegin(); it != created.rend(); ++it) fs::remove(*it, ec);  // only if empty
	}
};

void createDirs(const fs::path& p, std::vector<fs::path>& created)
{
	std::vector<fs::path> missing;
	for (fs::path q = p; !q.empty() && !fs::exists(q); q = q.parent_path()) missing.push_back(q);
	std::reverse(missing.begin(), missing.end());
	for (const auto& q : missing)
	{
		fs::create_directory(q);
		created.push_back(q);
	}
}
}  // namespace

KittiExporter::TResult KittiExporter::run(const std::string& inRawlog, const std::string& outRoot)
{
	mrpt::system::CTicTac timer;
	TResult res;

	io::Trajectory gt;
	if (!options.groundTruthTum.empty())
	{
		if (!fs::is_regular_file(options.groundTruthTum))
			throw DatasetError("'" + options.groundTruthTum + "': no such ground-truth file");
		gt = io::readTum(options.groundTruthTum);
		if (gt.empty()) throw DatasetError("'" + options.groundTruthTum + "': no poses");
		io::sortByTime(gt);
	}

	if (outRoot.empty()) throw DatasetError("the KITTI output root is empty (give a directory)");
	if (options.sequence.empty() || options.sequence.find('/') != std::string::npos || options.sequence == "." ||
		options.sequence == "..")
		throw DatasetError("sequence '" + options.sequence + "': not a sequence name (e.g. 00)");
	// No channels: the colour frames of the camera, paired and checked as
	// every command's are (throws naming the file if missing).
	filters::TChannelFrameSourceOptions sourceOpts;
	sourceOpts.camera = options.sensorLabel;
	filters::ChannelFrameSource source(inRawlog, {}, sourceOpts);
	const fs::path seqDir = fs::path(outRoot) / "sequences" / options.sequence;
	const fs::path posesPath = fs::path(outRoot) / "poses" / (options.sequence + ".txt");
	// The sequence folder and its poses file are put in place together, or
	// neither; folders made here go again if the export fails.
	StagingGuard guard;
	createDirs(seqDir.parent_path(), guard.created);
	if (!gt.empty()) createDirs(posesPath.parent_path(), guard.created);
	io::OutputTransaction outputs;
	outputs.addInput(inRawlog, "input rawlog");
	if (fs::is_directory(io::imagesDirFor(inRawlog)))
		outputs.addInput(io::imagesDirFor(inRawlog), "images folder of the input");
	if (!gt.empty()) outputs.addInput(options.groundTruthTum, "ground truth");
	fs::path staging;
	std::string posesTmp;
	try
	{
		staging = outputs.addDirectory(seqDir.string(), "sequence folder", "shadyloc export kitti sequence");
		if (!gt.empty()) posesTmp = outputs.addFile(posesPath.string(), "poses file");
	}
	catch (const std::invalid_argument& e)
	{
		throw DatasetError(e.what());
	}
	// Inside the staged folder only: never recreate it after an interrupt removed it.
	fs::create_directory(staging / "image_2");
	fs::create_directory(staging / "image_3");

	mrpt::img::TCamera left, right;
	double baseline = 0;
	std::vector<double> times;
	MRPT_LOG_INFO_STREAM(
		"Exporting '" << inRawlog << "' (sensor '" << options.sensorLabel << "') to '"
					  << seqDir.string() << "'");

	// The frame source checks that the calibration stays that of frame 0 (a
	// KITTI sequence has one calib.txt) and that the pair is rectified
	// (KITTI's P matrices describe a rectified pair); its errors name the
	// object and frame.
	filters::TChannelFrame fr;
	while (source.next(fr))
	{
		const size_t i = fr.index;
		const std::string& where = fr.where;
		if (i == 0)
		{
			left = fr.stereoCamera.leftCamera;
			right = fr.stereoCamera.rightCamera;
			baseline = fr.calib.baseline;
		}
		const cv::Mat& L = fr.left;
		const cv::Mat& R = fr.right;
		if (uint32_t(L.cols) != left.ncols || uint32_t(L.rows) != left.nrows)
			throw DatasetError(
				where + "image size " + std::to_string(L.cols) + "x" + std::to_string(L.rows) +
				" does not match the calibration " + std::to_string(left.ncols) + "x" +
				std::to_string(left.nrows));
		char name[32];
		std::snprintf(name, sizeof(name), "%06zu.png", i);
		for (auto [img, sub] : {std::pair{&L, "image_2"}, std::pair{&R, "image_3"}})
		{
			const std::string file = (staging / sub / name).string();
			if (!cv::imwrite(file, *img)) throw DatasetError(where + "cannot write '" + file + "'");
		}
		times.push_back(fr.timestamp);
		if (options.progressEvery > 0 && times.size() % options.progressEvery == 0)
			MRPT_LOG_INFO_FMT("  %5.1f%%  %zu frames exported", 100.0 * source.progress(), times.size());
	}
	if (times.empty()) throw DatasetError(source.noFramesMessage());

	// Poses: the ground-truth pose nearest in time to each frame.
	std::string poses;
	if (!gt.empty())
	{
		for (size_t i = 0; i < times.size(); i++)
		{
			auto it = std::lower_bound(
				gt.begin(), gt.end(), times[i], [](const io::TStampedPose& p, double t) { return p.t < t; });
			const io::TStampedPose* best = nullptr;
			if (it != gt.end()) best = &*it;
			if (it != gt.begin() && (!best || times[i] - std::prev(it)->t < best->t - times[i]))
				best = &*std::prev(it);
			if (!best || std::abs(best->t - times[i]) > options.gtTimeTolerance)
			{
				char msg[160];
				std::snprintf(
					msg, sizeof(msg), "frame %zu (t = %.9f s): no pose within %g s in ", i, times[i],
					options.gtTimeTolerance);
				throw DatasetError(std::string(msg) + "'" + options.groundTruthTum + "'");
			}
			poses += poseTo34(best->T) + "\n";
		}
	}

	{
		std::ofstream f(staging / "calib.txt");
		const TMatrix34 P2 = projectionFromCamera(left, {0, 0, 0});
		const TMatrix34 P3 = projectionFromCamera(right, {-baseline, 0, 0});
		f << matrixLine("P0", P2) << "\n"
		  << matrixLine("P1", P3) << "\n"
		  << matrixLine("P2", P2) << "\n"
		  << matrixLine("P3", P3) << "\n";
		f.close();
		if (!f) throw DatasetError("'" + (staging / "calib.txt").string() + "': write failed");
	}
	{
		std::ofstream f(staging / "times.txt");
		char buf[64];
		for (double t : times)
		{
			std::snprintf(buf, sizeof(buf), "%.9f\n", options.absoluteTimes ? t : t - times.front());
			f << buf;
		}
		f.close();
		if (!f) throw DatasetError("'" + (staging / "times.txt").string() + "': write failed");
	}

	if (!gt.empty())
	{
		std::ofstream f(posesTmp);
		f << poses;
		f.close();
		if (!f) throw DatasetError("'" + posesPath.string() + "': write failed");
		res.poses = true;
	}
	// Commit: the sequence (replacing an old one) and its poses together.
	outputs.commit();
	guard.dismissed = true;
	std::error_code ec;
	if (gt.empty() && fs::exists(posesPath, ec))
	{
		fs::remove(posesPath, ec);	// stale: belonged to the sequence just replaced
		MRPT_LOG_WARN_STREAM("removed stale poses '" << posesPath.string() << "'");
	}
	res.frames = times.size();
	res.seconds = timer.Tac();
	MRPT_LOG_INFO_FMT(
		"Wrote %zu frames to '%s'%s in %.2f s", res.frames, seqDir.string().c_str(),
		res.poses ? (" and '" + posesPath.string() + "'").c_str() : "", res.seconds);
	return res;
}

}  // namespace shadyloc::datasets
