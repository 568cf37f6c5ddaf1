/* ShadyLoc — TUM trajectory files. */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/Tum.h>

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/poses/CPose3D.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace shadyloc::io
{
Trajectory readTum(const std::string& path)
{
	std::error_code ec;
	if (std::filesystem::is_directory(path, ec))
		throw std::runtime_error("'" + path + "': is a directory, not a TUM trajectory file");
	if (!std::filesystem::is_regular_file(path, ec))
		throw std::runtime_error("'" + path + "': no such TUM trajectory file");
	std::ifstream f(path);
	if (!f) throw std::runtime_error("'" + path + "': cannot open TUM trajectory file");
	Trajectory out;
	std::string line;
	for (size_t n = 1; std::getline(f, line); n++)
	{
		const auto first = line.find_first_not_of(" \t\r");
		if (first == std::string::npos || line[first] == '#') continue;
		std::istringstream ss(line);
		double v[8];
		for (int i = 0; i < 8; i++)
			if (!(ss >> v[i]))
				throw std::runtime_error(
					"'" + path + "':" + std::to_string(n) +
					": expected 8 numbers 'timestamp tx ty tz qx qy qz qw', got '" + line + "'");
		std::string extra;
		if (ss >> extra)
			throw std::runtime_error(
				"'" + path + "':" + std::to_string(n) + ": more than 8 values: '" + line + "'");
		// Scalar last in the file; MRPT's quaternion takes the scalar first.
		const double norm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
		if (!(std::abs(norm - 1.0) < 1e-2))
			throw std::runtime_error(
				"'" + path + "':" + std::to_string(n) + ": quaternion norm " + std::to_string(norm) +
				" is not 1 (is the order qx qy qz qw?)");
		for (int i = 0; i < 4; i++)
			if (!std::isfinite(v[i]))
				throw std::runtime_error(
					"'" + path + "':" + std::to_string(n) + ": timestamp and position must be finite numbers: '" +
					line + "'");
		// Through MRPT's quaternion-to-matrix, as the library always read TUM
		// files: the same rotation bits as before the trajectory types merged.
		const mrpt::math::CQuaternionDouble q(v[7] / norm, v[4] / norm, v[5] / norm, v[6] / norm);
		const mrpt::poses::CPose3D pose(q, v[1], v[2], v[3]);
		out.push_back({v[0], toIsometry(pose)});
	}
	if (f.bad()) throw std::runtime_error("'" + path + "': read error");
	if (out.empty()) throw std::runtime_error("'" + path + "': holds no poses (empty TUM trajectory file)");
	return out;
}

std::string tumLine(const TStampedPose& p)
{
	// Straight from the rotation matrix (Eigen's Shepperd method), not via
	// yaw/pitch/roll, which loses precision near pitch = +-90 deg.
	Eigen::Quaterniond q(Eigen::Matrix3d(p.T.linear()));
	q.normalize();
	const double s = q.w() < 0 ? -1.0 : 1.0;	// q and -q: same rotation; print qw >= 0
	const Eigen::Vector3d x = p.T.translation();
	char buf[256];
	std::snprintf(
		buf, sizeof(buf), "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f", p.t, x.x(), x.y(), x.z(), s * q.x(),
		s * q.y(), s * q.z(), s * q.w());
	return buf;
}

void writeTum(const std::string& path, const Trajectory& traj, const std::string& comment)
{
	writeAtomically(path, [&](const std::string& tmp) {
		std::ofstream f(tmp);
		if (!f) throw std::runtime_error("'" + path + "': cannot create TUM file");
		if (!comment.empty()) f << "# " << comment << "\n";
		f << "# timestamp tx ty tz qx qy qz qw\n";
		for (const auto& p : traj) f << tumLine(p) << "\n";
		f.close();
		if (!f) throw std::runtime_error("'" + path + "': write failed (disk full?)");
	});
}

}  // namespace shadyloc::io
