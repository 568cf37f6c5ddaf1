/* ShadyLoc — streaming rawlog reading and atomic rawlog writing. */
#include <shadyloc/io/Rawlog.h>

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/string_utils.h>

#include <filesystem>
#include <system_error>

namespace fs = std::filesystem;

namespace shadyloc::io
{
std::string imagesDirFor(const std::string& rawlogPath)
{
	const fs::path p(rawlogPath);
	return (p.parent_path() / (p.stem().string() + "_Images")).string();
}

RawlogReader::RawlogReader(const std::string& path) : m_path(path)
{
	std::error_code ec;
	if (!fs::is_regular_file(path, ec))
		throw RawlogError("'" + path + "': no such rawlog file");
	m_totalBytes = fs::file_size(path, ec);
	std::string err;
	if (!m_in.open(path, err)) throw RawlogError("'" + path + "': cannot open: " + err);
	// Not CImage::setImagesPathBase(): that is one folder for the whole process.
	m_imagesDir = fs::absolute(imagesDirFor(path), ec).lexically_normal().string();
}

std::string RawlogReader::where(const std::string& what) const
{
	return "'" + m_path + "': object #" + std::to_string(index()) + ": " + what;
}

double RawlogReader::progress() const
{
	if (m_totalBytes == 0) return 1.0;
	return std::min(1.0, double(m_in.getPosition()) / double(m_totalBytes));
}

mrpt::serialization::CSerializable::Ptr RawlogReader::next()
{
	m_count++;	// index() now names the object being read
	try
	{
		auto arch = mrpt::serialization::archiveFrom(m_in);
		auto obj = arch.ReadObject();
		if (!obj) throw RawlogError(where("null object stored"));
		for (const auto& o : observationsIn(obj)) resolveExternalImages(*o, m_imagesDir);
		return obj;
	}
	catch (const mrpt::serialization::CExceptionEOF&)
	{
		// A clean end of file lands exactly on an object boundary. A gzip
		// stream cut short also reports EOF there: tell them apart by whether
		// the whole compressed file was consumed.
		m_count--;
		if (m_totalBytes > 0 && m_in.getPosition() + 8 < m_totalBytes)
			throw RawlogError(
				"'" + m_path + "': object #" + std::to_string(m_count) +
				": unexpected end of data before the end of the file (corrupt?)");
		return nullptr;
	}
	catch (const RawlogError&)
	{
		throw;
	}
	catch (const std::exception& e)
	{
		std::string msg = e.what();
		// MRPT exceptions nest messages with call traces; the innermost
		// "Message:" line says what went wrong.
		if (const auto pos = msg.rfind("Message:"); pos != std::string::npos)
		{
			const auto end = msg.find('\n', pos);
			msg = mrpt::system::trim(msg.substr(pos + 8, end == std::string::npos ? end : end - pos - 8));
		}
		if (msg.find("Stored object has class") != std::string::npos)
			msg += " (unknown class: load the plugin that defines it, or the file is corrupt)";
		else if (m_in.checkEOF())
			msg = "truncated object (file ends in the middle of it)";
		else
			msg = "corrupt data: " + msg;
		throw RawlogError(where(msg));
	}
}

std::vector<mrpt::obs::CObservation::Ptr> observationsIn(
	const mrpt::serialization::CSerializable::Ptr& obj)
{
	using namespace mrpt::obs;
	std::vector<CObservation::Ptr> out;
	if (auto sf = std::dynamic_pointer_cast<CSensoryFrame>(obj))
	{
		for (const auto& o : *sf) out.push_back(o);
	}
	else if (auto o = std::dynamic_pointer_cast<CObservation>(obj))
		out.push_back(o);
	return out;
}

void resolveExternalImages(mrpt::obs::CObservation& obs, const std::string& imagesDir)
{
	using namespace mrpt::obs;
	auto resolve = [&](mrpt::img::CImage& img) {
		if (!img.isExternallyStored()) return;
		const std::string name = img.getExternalStorageFile();
		if (name.empty() || fs::path(name).is_absolute()) return;
		img.setExternalStorage((fs::path(imagesDir) / name).lexically_normal().string());
	};
	if (auto* st = dynamic_cast<CObservationStereoImages*>(&obs))
	{
		resolve(st->imageLeft);
		resolve(st->imageRight);
		resolve(st->imageDisparity);
	}
	else if (auto* im = dynamic_cast<CObservationImage*>(&obs))
		resolve(im->image);
}

void loadExternalImages(mrpt::obs::CObservation& obs)
{
	using namespace mrpt::obs;
	auto load = [&](const mrpt::img::CImage& img, const char* which) {
		if (!img.isExternallyStored()) return;
		try
		{
			img.forceLoad();
		}
		catch (const std::exception&)
		{
			throw RawlogError(
				std::string("missing or unreadable external ") + which + " image '" +
				img.getExternalStorageFileAbsolutePath() + "' of sensor '" + obs.sensorLabel +
				"'");
		}
	};
	if (auto* st = dynamic_cast<CObservationStereoImages*>(&obs))
	{
		load(st->imageLeft, "left");
		if (st->hasImageRight) load(st->imageRight, "right");
		if (st->hasImageDisparity) load(st->imageDisparity, "disparity");
	}
	else if (auto* im = dynamic_cast<CObservationImage*>(&obs))
		load(im->image, "");
}

RawlogWriter::RawlogWriter(const std::string& path, bool externalImages)
	: m_path(path), m_externalImages(externalImages)
{
	const fs::path p(path);
	if (!p.parent_path().empty() && !fs::is_directory(p.parent_path()))
		throw RawlogError("'" + path + "': output directory does not exist");
	m_tmpPath = (p.parent_path() / ("." + p.filename().string() + ".tmp")).string();
	m_imagesDir = imagesDirFor(path);
	m_tmpImagesDir = m_imagesDir + ".tmp";
	m_out = std::make_unique<mrpt::io::CFileGZOutputStream>();
	if (!m_out->open(m_tmpPath, 1 /* fast compression */))
		throw RawlogError("'" + path + "': cannot create output file '" + m_tmpPath + "'");
	if (m_externalImages)
	{
		std::error_code ec;
		fs::remove_all(m_tmpImagesDir, ec);
		fs::create_directories(m_tmpImagesDir);
	}
}

RawlogWriter::~RawlogWriter()
{
	if (m_committed) return;
	m_out.reset();
	std::error_code ec;
	fs::remove(m_tmpPath, ec);
	if (m_externalImages) fs::remove_all(m_tmpImagesDir, ec);
}

void RawlogWriter::write(const mrpt::serialization::CSerializable& obj)
{
	auto arch = mrpt::serialization::archiveFrom(*m_out);
	arch << obj;
	m_written++;
}

void RawlogWriter::externalise(mrpt::img::CImage& img, const std::string& name)
{
	if (!m_externalImages) return;
	const std::string file = (fs::path(m_tmpImagesDir) / name).string();
	if (!img.saveToFile(file))
		throw RawlogError("'" + m_path + "': cannot write external image '" + file + "'");
	img.setExternalStorage(name);
}

void RawlogWriter::commit()
{
	m_out->close();
	m_out.reset();
	if (m_externalImages)
	{
		std::error_code ec;
		fs::remove_all(m_imagesDir, ec);
		fs::rename(m_tmpImagesDir, m_imagesDir);
	}
	fs::rename(m_tmpPath, m_path);
	m_committed = true;
}

}  // namespace shadyloc::io
