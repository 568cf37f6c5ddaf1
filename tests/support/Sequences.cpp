/* ShadyLoc tests: rendered stereo sequences shared between test processes. */
#include "Sequences.h"

#include "TestSupport.h"

#include <shadyloc/core/Units.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/sim/SyntheticCorridor.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace shadyloc::test
{
namespace
{
/** The corridor sequences the fixture writes: (frames, speed) of the VO
 * accuracy tests (test_vo_synthetic.cpp) and of the determinism tests. */
const std::vector<std::pair<int, double>> kCorridorFixtures = {{50, 0.1}, {24, 0.3}};

std::string corridorFile(const std::string& dir, int frames, double speed)
{
	return dir + "/corridor_" + std::to_string(frames) + "_" +
		   std::to_string(static_cast<int>(std::lround(speed * 1000))) + "mm.bin";
}

TStereoSequence renderCorridor(int frames, double speed)
{
	const sim::SyntheticCorridor corridor;
	TStereoSequence s;
	s.calib = corridor.calib();
	for (int k = 0; k < frames; k++)
	{
		const Eigen::Isometry3d T = sim::SyntheticCorridor::examplePose(k, speed);
		cv::Mat l, r;
		corridor.render(T, l, r, static_cast<uint32_t>(k));
		s.left.push_back(l);
		s.right.push_back(r);
		s.t.push_back(0.1 * k);
		s.T_world_left.push_back(T);
	}
	return s;
}

// The fixture file: a magic, then per frame both images as raw bytes. Poses,
// times and the calibration are recomputed (they are exact formulas).
constexpr char kMagic[8] = {'S', 'L', 'C', 'O', 'R', 'R', '1', '\n'};

void writeCorridorFile(const std::string& path, const TStereoSequence& s)
{
	io::writeAtomically(path, [&](const std::string& tmp) {
		std::ofstream f(tmp, std::ios::binary);
		f.write(kMagic, sizeof(kMagic));
		const int32_t hdr[3] = {static_cast<int32_t>(s.left.size()), s.left[0].cols, s.left[0].rows};
		f.write(reinterpret_cast<const char*>(hdr), sizeof(hdr));
		for (size_t k = 0; k < s.left.size(); k++)
			for (const cv::Mat* m : {&s.left[k], &s.right[k]})
			{
				CV_Assert(m->type() == CV_8UC3 && m->isContinuous());
				f.write(reinterpret_cast<const char*>(m->data), static_cast<std::streamsize>(m->total() * 3));
			}
		if (!f) throw std::runtime_error("cannot write '" + tmp + "'");
	});
}

TStereoSequence readCorridorFile(const std::string& path, int frames, double speed)
{
	std::ifstream f(path, std::ios::binary);
	char magic[8];
	int32_t hdr[3];
	if (!f.read(magic, 8) || std::string(magic, 8) != std::string(kMagic, 8) ||
		!f.read(reinterpret_cast<char*>(hdr), sizeof(hdr)) || hdr[0] != frames)
		throw std::runtime_error(
			"'" + path + "': missing or not a corridor fixture of " + std::to_string(frames) +
			" frames (its ctest fixture setup, TestFixtures.WriteCorridorSequences, did not run?)");
	TStereoSequence s;
	s.calib = sim::SyntheticCorridor().calib();
	for (int k = 0; k < frames; k++)
	{
		cv::Mat l(hdr[2], hdr[1], CV_8UC3), r(hdr[2], hdr[1], CV_8UC3);
		for (cv::Mat* m : {&l, &r})
			if (!f.read(reinterpret_cast<char*>(m->data), static_cast<std::streamsize>(m->total() * 3)))
				throw std::runtime_error("'" + path + "': truncated at frame " + std::to_string(k));
		s.left.push_back(l);
		s.right.push_back(r);
		s.t.push_back(0.1 * k);
		s.T_world_left.push_back(sim::SyntheticCorridor::examplePose(k, speed));
	}
	return s;
}

/** TUM lines `t tx ty tz qx qy qz qw`, '#' comments. */
void readTumInto(const std::string& path, TStereoSequence& s)
{
	std::ifstream f(path);
	if (!f) throw std::runtime_error("'" + path + "': cannot open");
	std::string line;
	while (std::getline(f, line))
	{
		if (line.empty() || line[0] == '#') continue;
		std::istringstream ls(line);
		double t, x, y, z, qx, qy, qz, qw;
		if (!(ls >> t >> x >> y >> z >> qx >> qy >> qz >> qw))
			throw std::runtime_error("'" + path + "': bad line '" + line + "'");
		Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
		T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
		T.translation() = Eigen::Vector3d(x, y, z);
		s.t.push_back(t);
		s.T_world_left.push_back(T);
	}
}

TStereoSequence readSimDir(const std::string& dir, const std::string& traversal)
{
	TStereoSequence s;
	const auto frames = readStereoFrames(dir + "/" + traversal + ".rawlog");
	if (frames.empty())
		throw std::runtime_error("'" + dir + "/" + traversal + ".rawlog': no stereo frames");
	s.calib = geometry::TStereoCalib::FromObservation(*frames[0]);
	for (const auto& o : frames)
	{
		s.left.push_back(o->imageLeft.asCvMat<cv::Mat>(mrpt::img::DEEP_COPY));
		s.right.push_back(o->imageRight.asCvMat<cv::Mat>(mrpt::img::DEEP_COPY));
	}
	readTumInto(dir + "/" + traversal + ".tum", s);
	if (s.t.size() != s.left.size())
		throw std::runtime_error("'" + dir + "': " + traversal + " ground truth and frames differ in number");
	return s;
}
}  // namespace

Eigen::Isometry3d corridorPose(double z, double x, double yawDeg)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = Eigen::AngleAxisd(yawDeg * core::kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
	T.translation() = Eigen::Vector3d(x, 0.1, z);
	return T;
}

sim::TSimOptions smallSimOptions(int w, int h)
{
	auto o = sim::TSimOptions::FromFile(sourcePath("config/sim.ini"));
	o.camera.width = w;
	o.camera.height = h;
	return o;
}

std::string fixtureDir()
{
	const char* d = std::getenv("SHADYLOC_FIXTURE_DIR");
	return d ? d : "";
}

void writeCorridorFixtures(const std::string& dir)
{
	fs::create_directories(dir);
	for (const auto& [frames, speed] : kCorridorFixtures)
		writeCorridorFile(corridorFile(dir, frames, speed), renderCorridor(frames, speed));
}

const TStereoSequence& corridorSequence(int frames, double speed)
{
	static std::mutex mx;
	static std::map<std::pair<int, double>, TStereoSequence> cache;
	std::lock_guard<std::mutex> lock(mx);
	const auto key = std::make_pair(frames, speed);
	if (auto it = cache.find(key); it != cache.end()) return it->second;
	bool provided = false;
	for (const auto& k : kCorridorFixtures) provided |= k == key;
	const std::string dir = fixtureDir();
	return cache[key] = (provided && !dir.empty()) ? readCorridorFile(corridorFile(dir, frames, speed), frames, speed)
												  : renderCorridor(frames, speed);
}

std::string simSequenceDir(const std::string& traversal)
{
	std::string dir = fixtureDir().empty() ? "" : fixtureDir() + "/sim";
	if (!dir.empty() && fs::exists(dir + "/" + traversal + ".rawlog")) return dir;
	if (!fixtureDir().empty())
		throw std::runtime_error(
			"'" + dir + "/" + traversal + ".rawlog' missing: its ctest fixture setup "
			"(Fixture.SimSequences) did not run or does not render '" + traversal + "'");
	// Outside ctest: render with the same command the fixture runs, once per process.
	static std::mutex mx;
	static std::map<std::string, std::string> rendered;
	std::lock_guard<std::mutex> lock(mx);
	if (auto it = rendered.find(traversal); it != rendered.end()) return it->second;
	dir = tempDir("sim_sequence_" + traversal);
	std::string out;
	const std::string cmd = appPath() + " sim -q -c " + std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini -o " + dir +
							" --traversals " + traversal + " --frames " + std::to_string(kSimFixtureFrames);
	if (runCommand(cmd, &out) != 0) throw std::runtime_error(cmd + " failed:\n" + out);
	return rendered[traversal] = dir;
}

const TStereoSequence& simSequence(const std::string& traversal)
{
	static std::mutex mx;
	static std::map<std::string, TStereoSequence> cache;
	std::lock_guard<std::mutex> lock(mx);
	if (auto it = cache.find(traversal); it != cache.end()) return it->second;
	return cache[traversal] = readSimDir(simSequenceDir(traversal), traversal);
}

}  // namespace shadyloc::test
