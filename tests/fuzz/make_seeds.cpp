/* Writes the fuzz seed corpora from the project's own data, so no binary
 * corpus is kept in the repository:
 *   make_seeds SOURCE_DIR OUT_DIR
 * OUT_DIR/rawlog: small synthetic stereo rawlogs (bare observations and
 *   sensory frames, gzip and plain, external images, filtered);
 * OUT_DIR/image: tiny PNG/JPEG/PPM/PGM/BMP/TIFF files in the formats read;
 * OUT_DIR/settings: the .ini files of config/; OUT_DIR/tum: TUM trajectories;
 * OUT_DIR/map: keyframe maps (empty, and the golden populated one) and, for
 *   the header-first check, the golden header with absurd sizes, cut short,
 *   of another class, and files that are no map. */
#include <shadyloc/Registration.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/io/Rawlog.h>

#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <iostream>

namespace fs = std::filesystem;
using namespace shadyloc;

namespace
{
mrpt::obs::CObservationStereoImages::Ptr frame(int i, int w, int h)
{
	cv::Mat l(h, w, CV_8UC3), r(h, w, CV_8UC3);
	cv::randu(l, 0, 255);
	cv::randu(r, 0, 255);
	auto o = mrpt::obs::CObservationStereoImages::Create();
	o->sensorLabel = "CAMERA";
	o->timestamp = mrpt::Clock::fromDouble(1000.0 + 0.1 * i);
	o->imageLeft = mrpt::img::CImage(l, mrpt::img::DEEP_COPY);
	o->imageRight = mrpt::img::CImage(r, mrpt::img::DEEP_COPY);
	o->hasImageRight = true;
	o->leftCamera.ncols = o->rightCamera.ncols = w;
	o->leftCamera.nrows = o->rightCamera.nrows = h;
	o->leftCamera.setIntrinsicParamsFromValues(40, 40, w / 2.0, h / 2.0);
	o->rightCamera = o->leftCamera;
	o->rightCameraPose = mrpt::poses::CPose3DQuat(mrpt::poses::CPose3D(0.12, 0, 0, 0, 0, 0));
	return o;
}
}  // namespace

namespace
{
void writeBytes(const fs::path& p, const std::string& bytes)
{
	std::ofstream f(p, std::ios::binary);
	f << bytes;
}

/** Seeds for the map loader's header-first check: the golden map's header
 * with absurd block sizes, cut inside and just after the header, another
 * class's name, and files that are no map (a rawlog, an image, text). */
void writeMapHeaderSeeds(const fs::path& src, const fs::path& dir)
{
	std::ifstream in(src / "tests/golden/CKeyframeMap.bin", std::ios::binary);
	const std::string golden((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
	if (golden.size() < 64) return;
	const size_t head = 1 + (static_cast<unsigned char>(golden[0]) & 0x7f) + 1;  // tag, class name, version
	for (const size_t at : {head + 1, head + 9})  // the first block's size and the next field
	{
		std::string huge = golden;
		for (size_t i = at; i < at + 8; i++) huge[i] = '\xff';
		writeBytes(dir / ("huge_size_at_" + std::to_string(at) + ".kfmap"), huge);
	}
	writeBytes(dir / "header_only.kfmap", golden.substr(0, head));
	writeBytes(dir / "cut_in_header.kfmap", golden.substr(0, head / 2));
	std::string other = golden;
	other[head - 2] = 'X';	// "shadyloc::CKeyframeMaX": another class
	writeBytes(dir / "other_class.kfmap", other);
	writeBytes(dir / "text.kfmap", "[map]\nkf_spacing_m = 1.5\n");
	for (const char* f : {"rawlog/plain.rawlog", "image/c.png"})
		if (fs::exists(dir.parent_path() / f))
			fs::copy_file(dir.parent_path() / f, dir / ("not_a_map_" + fs::path(f).filename().string()),
						  fs::copy_options::overwrite_existing);
}
}  // namespace

int main(int argc, char** argv)
{
	if (argc != 3)
	{
		std::cerr << "usage: make_seeds SOURCE_DIR OUT_DIR\n";
		return 2;
	}
	registerAllClasses();
	const fs::path src(argv[1]), out(argv[2]);
	for (const char* d : {"rawlog", "image", "settings", "tum", "map"}) fs::create_directories(out / d);

	// Rawlogs (tiny images: the fuzzer's inputs stay small).
	{
		io::RawlogWriter w((out / "rawlog/bare.rawlog").string());
		for (int i = 0; i < 2; i++) w.write(*frame(i, 8, 6));
		w.commit();
	}
	{
		io::RawlogWriter w((out / "rawlog/sf.rawlog").string());
		for (int i = 0; i < 2; i++)
		{
			mrpt::obs::CActionCollection acts;
			mrpt::obs::CSensoryFrame sf;
			sf.insert(frame(i, 8, 6));
			w.write(acts);
			w.write(sf);
		}
		w.commit();
	}
	{
		mrpt::io::CFileOutputStream f((out / "rawlog/plain.rawlog").string());
		auto a = mrpt::serialization::archiveFrom(f);
		a << *frame(0, 6, 4);
	}
	{
		const fs::path tmp = fs::temp_directory_path() / "shadyloc_seed_ext";
		fs::remove_all(tmp);
		fs::create_directories(tmp);
		io::RawlogWriter w((tmp / "ext.rawlog").string(), true);
		auto o = frame(0, 8, 6);
		w.externalise(o->imageLeft, "L0.png");
		w.externalise(o->imageRight, "R0.png");
		w.write(*o);
		w.commit();
		fs::copy_file(tmp / "ext.rawlog", out / "rawlog/external.rawlog", fs::copy_options::overwrite_existing);
		filters::RawlogFilterProcessor p;
		p.setMinLoggingLevel(mrpt::system::LVL_ERROR);
		io::RawlogWriter w2((tmp / "in.rawlog").string());
		w2.write(*frame(0, 8, 6));
		w2.commit();
		p.run((tmp / "in.rawlog").string(), (tmp / "filtered.rawlog").string(), filters::FilterPipeline::Default());
		fs::copy_file(tmp / "filtered.rawlog", out / "rawlog/filtered.rawlog", fs::copy_options::overwrite_existing);
		fs::remove_all(tmp);
	}

	// Images in every format the checked reader knows.
	cv::Mat colour(12, 16, CV_8UC3), grey(12, 16, CV_8UC1), alpha(12, 16, CV_8UC4), deep(12, 16, CV_16UC1);
	cv::randu(colour, 0, 255);
	cv::randu(grey, 0, 255);
	cv::randu(alpha, 0, 255);
	cv::randu(deep, 0, 65535);
	const auto img = [&](const std::string& name, const cv::Mat& m, const std::vector<int>& params = {}) {
		if (!cv::imwrite((out / "image" / name).string(), m, params)) std::cerr << "cannot write seed " << name << "\n";
	};
	img("c.png", colour);
	img("g.png", grey);
	img("a.png", alpha);
	img("d16.png", deep);
	img("c.jpg", colour);
	img("g.jpg", grey);
	img("p.jpg", colour, {cv::IMWRITE_JPEG_PROGRESSIVE, 1});
	img("c.ppm", colour);
	img("g.pgm", grey);
	img("c.bmp", colour);
	img("c.tif", colour);

	// Settings: the project's own .ini files.
	for (const auto& e : fs::directory_iterator(src / "config"))
		if (e.path().extension() == ".ini")
			fs::copy_file(e.path(), out / "settings" / e.path().filename(), fs::copy_options::overwrite_existing);

	// TUM trajectories.
	io::Trajectory t;
	for (int i = 0; i < 4; i++)
		t.push_back({1000.0 + i, io::toIsometry(mrpt::poses::CPose3D(i, 0.5 * i, 0, 0.1 * i, 0, 0))});
	io::writeTum((out / "tum/a.tum").string(), t, "seed");
	// Keyframe maps: an empty one, and the populated map of the golden files.
	CKeyframeMap::Create()->saveToFile((out / "map/empty.kfmap").string());
	if (fs::exists(src / "tests/golden/CKeyframeMap.bin"))
		fs::copy_file(src / "tests/golden/CKeyframeMap.bin", out / "map/golden.kfmap", fs::copy_options::overwrite_existing);
	writeMapHeaderSeeds(src, out / "map");
	std::cout << "fuzz seeds written to " << out.string() << "\n";
	return 0;
}
