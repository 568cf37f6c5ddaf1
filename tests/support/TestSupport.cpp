/* ShadyLoc tests: support code. */
#include "TestSupport.h"

#include <shadyloc/io/Rawlog.h>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/core.hpp>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <random>

#include <fcntl.h>
#include <sys/types.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace shadyloc::test
{
std::string sharedDataDir()
{
	const std::string d = SHADYLOC_SHARED_DATA_DIR;
	return fs::is_directory(d) ? d : std::string();
}

std::string tempDir(const std::string& name)
{
	const char* base = std::getenv("SHADYLOC_TMP");
	fs::path p = fs::path(base ? base : fs::temp_directory_path().string()) / ("shadyloc_" + name);
	fs::remove_all(p);
	fs::create_directories(p);
	return p.string();
}

int runCommand(const std::string& cmd, std::string* output)
{
	std::string full = cmd + " 2>&1";
	FILE* pipe = popen(full.c_str(), "r");
	if (!pipe) return -1;
	std::array<char, 4096> buf;
	std::string out;
	size_t n;
	while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
	const int status = pclose(pipe);
	if (output) *output = out;
	return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<mrpt::obs::CObservationStereoImages::Ptr> readStereoFrames(const std::string& rawlog)
{
	std::vector<mrpt::obs::CObservationStereoImages::Ptr> out;
	io::RawlogReader r(rawlog);
	while (auto obj = r.next())
		for (auto& o : io::observationsIn(obj))
			if (auto s = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(o))
			{
				io::loadExternalImages(*s);
				out.push_back(s);
			}
	return out;
}

// SHADYLOC_TEST_APP runs the command-line tests against another build (an
// older one, to see a regression test fail without its fix).
int spawnApp(const std::vector<std::string>& args, const std::string& log)
{
	const pid_t pid = fork();
	if (pid == 0)
	{
		const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(fd, 1);
		dup2(fd, 2);
		std::vector<std::string> copy = args;
		std::string app = appPath();
		std::vector<char*> argv{app.data()};
		for (auto& a : copy) argv.push_back(a.data());
		argv.push_back(nullptr);
		execv(app.c_str(), argv.data());
		_exit(127);
	}
	return pid;
}

std::string fileContents(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	std::ostringstream s;
	s << f.rdbuf();
	return s.str();
}

void writeFileContents(const std::string& path, const std::string& contents)
{
	std::ofstream f(path, std::ios::binary | std::ios::trunc);
	f << contents;
}

Bytes fileBytes(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	return Bytes(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const Bytes& b)
{
	std::ofstream f(path, std::ios::binary | std::ios::trunc);
	f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

std::map<std::string, std::string> snapshot(const std::string& path)
{
	std::map<std::string, std::string> s;
	if (fs::is_regular_file(path)) s["."] = fileContents(path);
	else if (fs::is_directory(path))
		for (const auto& e : fs::recursive_directory_iterator(path))
			if (e.is_regular_file()) s[fs::relative(e.path(), path).string()] = fileContents(e.path().string());
	return s;
}

bool updatingGolden()
{
	const char* e = std::getenv("SHADYLOC_UPDATE_GOLDEN");
	return e && *e && std::string(e) != "0";
}

std::string errorOf(const std::function<void()>& f)
{
	try
	{
		f();
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
	return "";
}

bool samePixels(const cv::Mat& a, const cv::Mat& b)
{
	return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

geometry::TStereoCalib stereoCalib()
{
	geometry::TStereoCalib c;
	c.fx = c.fy = 400;
	c.cx = 256;
	c.cy = 192;
	c.cxR = 256;
	c.baseline = 0.12;
	return c;
}

std::string defaultDatasetDir()
{
	auto complete = [](const std::string& dir) {
		for (const char* t : {"evening_warm", "morning_low_sun", "noon", "overcast"})
			for (const char* ext : {".rawlog", ".tum"})
				if (!std::filesystem::is_regular_file(dir + "/" + t + ext)) return false;
		return true;
	};
	const std::string generated = std::string(SHADYLOC_SOURCE_DIR) + "/rawlogs/generated";
	if (complete(generated)) return generated;
	const char* fixtures = std::getenv("SHADYLOC_FIXTURE_DIR");
	if (fixtures && *fixtures)
	{
		const std::string dir = std::string(fixtures) + "/default_data";
		if (std::filesystem::exists(dir + "/.complete") && complete(dir)) return dir;
	}
	return {};
}

std::string appPath()
{
	const char* other = std::getenv("SHADYLOC_TEST_APP");
	return other && *other ? other : SHADYLOC_APP;
}
std::string pluginPath() { return SHADYLOC_PLUGIN; }
std::string sourcePath(const std::string& rel) { return std::string(SHADYLOC_SOURCE_DIR) + "/" + rel; }

mrpt::obs::CObservationStereoImages stereoObservation(
	const cv::Mat& left, const cv::Mat& right, const geometry::TStereoCalib& c, double timestamp,
	const std::string& label)
{
	mrpt::obs::CObservationStereoImages obs;
	obs.sensorLabel = label;
	obs.timestamp = mrpt::Clock::fromDouble(timestamp);
	obs.imageLeft = mrpt::img::CImage(left, mrpt::img::DEEP_COPY);
	obs.imageRight = mrpt::img::CImage(right, mrpt::img::DEEP_COPY);
	obs.hasImageRight = true;
	obs.leftCamera.ncols = obs.rightCamera.ncols = left.cols;
	obs.leftCamera.nrows = obs.rightCamera.nrows = left.rows;
	obs.leftCamera.setIntrinsicParamsFromValues(c.fx, c.fy, c.cx, c.cy);
	obs.rightCamera = obs.leftCamera;
	obs.rightCameraPose = mrpt::poses::CPose3DQuat(mrpt::poses::CPose3D(c.baseline, 0, 0, 0, 0, 0));
	return obs;
}

mrpt::obs::CObservationStereoImages::Ptr syntheticStereoFrame(int frame, int w, int h)
{
	std::mt19937 rng(1234);	 // same texture every frame: a static scene
	std::uniform_int_distribution<int> u(40, 220);
	cv::Mat left(h, w, CV_8UC3), right(h, w, CV_8UC3);
	const int disparity = 6;
	// Coloured 4x4 blocks (BGR), then a moving shadow band: sky light only,
	// weaker and bluer than sun + sky.
	for (int y = 0; y < h; y += 4)
		for (int x = 0; x < w + disparity; x += 4)
		{
			const cv::Vec3b c(u(rng), u(rng), u(rng));
			for (int dy = 0; dy < 4 && y + dy < h; dy++)
				for (int dx = 0; dx < 4; dx++)
				{
					const int xl = x + dx;
					if (xl < w) left.at<cv::Vec3b>(y + dy, xl) = c;
					const int xr = xl - disparity;
					if (xr >= 0 && xr < w) right.at<cv::Vec3b>(y + dy, xr) = c;
				}
		}
	const int x0 = (10 * frame) % w, x1 = x0 + w / 4;
	for (cv::Mat* m : {&left, &right})
		for (int y = 0; y < h; y++)
			for (int x = x0; x < std::min(x1, w); x++)
			{
				auto& p = m->at<cv::Vec3b>(y, x);
				p = cv::Vec3b(
					cv::saturate_cast<uint8_t>(p[0] * 0.55), cv::saturate_cast<uint8_t>(p[1] * 0.40),
					cv::saturate_cast<uint8_t>(p[2] * 0.30));
			}
	auto obs = mrpt::obs::CObservationStereoImages::Create();
	obs->sensorLabel = "CAMERA";
	obs->timestamp = mrpt::Clock::fromDouble(1000.0 + 0.1 * frame);
	obs->imageLeft = mrpt::img::CImage(left, mrpt::img::DEEP_COPY);
	obs->imageRight = mrpt::img::CImage(right, mrpt::img::DEEP_COPY);
	obs->hasImageRight = true;
	obs->leftCamera.ncols = obs->rightCamera.ncols = w;
	obs->leftCamera.nrows = obs->rightCamera.nrows = h;
	obs->leftCamera.setIntrinsicParamsFromValues(200, 200, w / 2.0, h / 2.0);
	obs->rightCamera = obs->leftCamera;
	obs->rightCameraPose = mrpt::poses::CPose3DQuat(mrpt::poses::CPose3D(0.12, 0, 0, 0, 0, 0));
	return obs;
}

void writeSyntheticRawlog(const std::string& path, int n, bool sensoryFrames, int w, int h)
{
	mrpt::io::CFileGZOutputStream f(path);
	auto arch = mrpt::serialization::archiveFrom(f);
	for (int i = 0; i < n; i++)
	{
		auto obs = syntheticStereoFrame(i, w, h);
		if (sensoryFrames)
		{
			mrpt::obs::CActionCollection acts;
			mrpt::obs::CSensoryFrame sf;
			sf.insert(obs);
			arch << acts << sf;
		}
		else
			arch << *obs;
	}
}

}  // namespace shadyloc::test
