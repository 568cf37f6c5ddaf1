/* ShadyLoc — streaming rawlog reading and atomic rawlog writing. */
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/core/Errors.h>
#include <shadyloc/io/AllocationBound.h>
#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/OutputTransaction.h>

#include "CheckedInputStream.h"
#include "JpegCodecs.h"

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

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
	m_in = std::make_unique<detail::CheckedInputStream>(path);
	// Not CImage::setImagesPathBase(): that is one folder for the whole process.
	std::error_code ec;
	m_imagesDir = fs::absolute(imagesDirFor(path), ec).lexically_normal().string();
}

RawlogReader::~RawlogReader() = default;

std::string RawlogReader::where(const std::string& what) const
{
	return "'" + m_path + "': object #" + std::to_string(index()) + ": " + what;
}

double RawlogReader::progress() const
{
	const uint64_t total = m_in->getTotalBytesCount();
	if (total == 0) return 1.0;
	return std::min(1.0, double(m_in->filePosition()) / double(total));
}

namespace
{
/** The allocation bound while an object is deserialised: no single
 * allocation larger than the bytes left in the stream (plus a little for
 * containers whose elements are larger in memory than on disk). */
[[maybe_unused]] bool withinStream(size_t bytes, void* stream)
{
	constexpr size_t kSlack = 64 * 1024;
	auto* in = static_cast<detail::CheckedInputStream*>(stream);
	return bytes <= kSlack || in->hasAtLeast(bytes - kSlack);
}
}  // namespace

mrpt::serialization::CSerializable::Ptr RawlogReader::next()
{
	m_count++;	// index() now names the object being read
	try
	{
		// A clean end lies exactly between two objects, with the trailer of a
		// gzip stream read and checked; anything else throws below.
		if (m_in->atCleanEnd())
		{
			m_count--;
			return nullptr;
		}
	}
	catch (const RawlogError& e)
	{
		m_count--;
		throw RawlogError(
			std::string(e.what()) +
			(m_count == 0 ? std::string(" (before the first object)")
						  : " (after object #" + std::to_string(m_count - 1) + ")"));
	}
	m_in->clearFailure();
	try
	{
		detail::JpegCodecReaper jpegCodecs;  // MRPT's JPEG decoder leaks on any exception
#ifndef SHADYLOC_NO_LENGTH_BOUND
		AllocationBound bound(&withinStream, m_in.get());
#endif
		auto arch = mrpt::serialization::archiveFrom(*m_in);
		auto obj = arch.ReadObject();
		if (!obj) throw RawlogError(where("null object stored"));
		for (const auto& o : observationsIn(obj)) resolveExternalImages(*o, m_imagesDir);
		return obj;
	}
	catch (const RawlogError& e)
	{
		if (!m_in->failure().empty()) throw RawlogError(where(m_in->failure()));
		throw;
	}
	catch (const std::exception& e)
	{
		// The stream's own diagnosis first: MRPT wraps what it throws.
		if (!m_in->failure().empty()) throw RawlogError(where(m_in->failure()));
		if (const size_t refused = AllocationBound::lastRefused())
			throw RawlogError(where(
				"corrupt data: a length field asks for " + std::to_string(refused) +
				" bytes, more than remain in the file"));
		std::string msg = core::mrptReason(e.what());
		if (msg.find("Stored object has class") != std::string::npos)
			msg += " (unknown class: load the plugin that defines it, or the file is corrupt)";
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
		const std::string file = img.getExternalStorageFileAbsolutePath();
		const std::string what = std::string("external ") + which + (*which ? " " : "") + "image of sensor '" +
			obs.sensorLabel + "'";
		try
		{
			// The file's structure first: OpenCV decodes a truncated JPEG
			// without complaint, filling the missing rows grey.
			checkImageFile(file);
			img.forceLoad();
		}
		catch (const ImageFileError& e)
		{
			throw RawlogError(what + ": " + e.what());
		}
		catch (const std::exception&)
		{
			throw RawlogError(what + ": '" + file + "': missing or unreadable");
		}
		if (img.asCvMatRef().empty()) throw RawlogError(what + ": '" + file + "': cannot decode");
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

std::string externalImagesOf(const mrpt::obs::CObservation& obs)
{
	using namespace mrpt::obs;
	std::string s;
	auto add = [&](const mrpt::img::CImage& img, const char* which) {
		if (!img.isExternallyStored()) return;
		s += std::string(s.empty() ? " (" : ", ") + which + "image '" + img.getExternalStorageFileAbsolutePath() + "'";
	};
	if (auto* st = dynamic_cast<const CObservationStereoImages*>(&obs))
	{
		add(st->imageLeft, "left ");
		if (st->hasImageRight) add(st->imageRight, "right ");
	}
	else if (auto* im = dynamic_cast<const CObservationImage*>(&obs))
		add(im->image, "");
	return s.empty() ? s : s + ")";
}

RawlogWriter::RawlogWriter(const std::string& path, bool externalImages, OutputTransaction* tx)
	: m_path(path), m_externalImages(externalImages)
{
	if (!tx)
	{
		m_ownTx = std::make_unique<OutputTransaction>();
		tx = m_ownTx.get();
	}
	m_tx = tx;
	m_imagesDir = imagesDirFor(path);
	try
	{
		m_tmpPath = m_tx->addFile(path, "output rawlog");
		if (m_externalImages) stagedImagesDir();
	}
	catch (const std::invalid_argument& e)
	{
		throw RawlogError(e.what());
	}
	m_out = std::make_unique<mrpt::io::CFileGZOutputStream>();
	if (!m_out->open(m_tmpPath, 1 /* fast compression */))
		throw RawlogError("'" + path + "': cannot create output file '" + m_tmpPath + "'");
}

RawlogWriter::~RawlogWriter() = default;  // the transaction removes what was not committed

const std::string& RawlogWriter::stagedImagesDir()
{
	if (m_tmpImagesDir.empty())
	{
		try
		{
			m_tmpImagesDir = m_tx->addDirectory(m_imagesDir, "'" + m_path + "': its images folder", "shadyloc rawlog images folder");
		}
		catch (const std::invalid_argument& e)
		{
			// Images folders are named after the rawlog's stem.
			throw RawlogError(std::string(e.what()) + " (give the output a name whose stem differs from the input's)");
		}
	}
	return m_tmpImagesDir;
}

void RawlogWriter::write(const mrpt::serialization::CSerializable& obj)
{
	auto arch = mrpt::serialization::archiveFrom(*m_out);
	arch << obj;
	m_written++;
}

namespace
{
/** Creates the folders between `root` (which must exist) and `dir`, never
 * `root` itself: once an interrupt has removed the staged images folder, a
 * writer still running must not bring it back (it would be left behind). */
void createFoldersInside(const fs::path& root, const fs::path& dir)
{
	std::error_code ec;
	const fs::path rel = dir.lexically_relative(root);
	fs::path at = root;
	for (const auto& part : rel)
	{
		if (part == "." || part.empty()) continue;
		at /= part;
		fs::create_directory(at, root, ec);  // fails, as it should, when `root` is gone
	}
}
}  // namespace

void RawlogWriter::externalise(mrpt::img::CImage& img, const std::string& name)
{
	if (!m_externalImages) return;
	const fs::path file = fs::path(stagedImagesDir()) / name;
	std::error_code ec;
	if (fs::exists(file, ec))
		throw RawlogError("'" + m_path + "': two images would be written as '" + name + "'");
	createFoldersInside(stagedImagesDir(), file.parent_path());
	if (!img.saveToFile(file.string()))
		throw RawlogError("'" + m_path + "': cannot write external image '" + file.string() + "'");
	img.setExternalStorage(name);
}

void RawlogWriter::carryExternalImage(mrpt::img::CImage& img, const std::string& sourceImagesDir)
{
	if (!img.isExternallyStored()) return;
	std::string name = img.getExternalStorageFile();
	if (name.empty()) return;
	if (fs::path(name).is_absolute())
	{
		// The reader resolved it against the input's images folder: carry it
		// under its name relative to that folder; a path elsewhere stays as is.
		std::error_code ec;
		const fs::path base = fs::absolute(sourceImagesDir, ec).lexically_normal();
		const fs::path rel = fs::path(name).lexically_normal().lexically_relative(base);
		if (rel.empty() || *rel.begin() == "..") return;
		name = rel.string();
		img.setExternalStorage(name);
	}
	const fs::path src = fs::path(sourceImagesDir) / name;
	const fs::path dst = fs::path(stagedImagesDir()) / name;
	std::error_code ec;
	if (fs::exists(dst, ec))
	{
		if (fs::equivalent(src, dst, ec)) return;  // carried already (one image in several observations)
		throw RawlogError("'" + m_path + "': two images would be written as '" + name + "'");
	}
	if (!fs::is_regular_file(src, ec))
		throw RawlogError("external image '" + src.string() + "' is missing");
	createFoldersInside(stagedImagesDir(), dst.parent_path());
	// A hard link costs nothing; across file systems, a copy.
	fs::create_hard_link(src, dst, ec);
	if (ec)
	{
		ec.clear();
		fs::copy_file(src, dst, ec);
		if (ec)
			throw RawlogError(
				"'" + m_path + "': cannot copy external image '" + src.string() + "' to '" + dst.string() +
				"': " + ec.message());
	}
}

void RawlogWriter::commit()
{
	if (m_committed) return;
	m_out->close();
	m_out.reset();
	if (m_ownTx) m_ownTx->commit();
	m_committed = true;
}

}  // namespace shadyloc::io
