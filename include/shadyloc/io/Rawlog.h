/* ShadyLoc — streaming rawlog reading and atomic rawlog writing.
 *
 * MRPT's own readers stop at the first object they cannot read and report
 * success; these never do: every failure names the file, the object index and
 * the reason. Reading is checked end to end: a gzip stream must end with its
 * trailer (CRC-32 and length match), the last object must be whole, and no
 * length field may make the reader allocate more than remains in the stream.
 * Rawlogs reach gigabytes, so both sides hold one object at a time.
 */
#pragma once

#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/serialization/CSerializable.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace shadyloc::io
{
namespace detail
{
class CheckedInputStream;
}
class OutputTransaction;

/** Error while reading or writing a rawlog; what() names file, object, reason. */
class RawlogError : public std::runtime_error
{
   public:
	using std::runtime_error::runtime_error;
};

/** `<dir>/<stem>_Images`: where MRPT keeps a rawlog's external images. */
std::string imagesDirFor(const std::string& rawlogPath);

/** Reads top-level objects of a rawlog (either style: bare observations, or
 * CActionCollection/CSensoryFrame pairs) one at a time.
 *
 * External images: each reader resolves the relative image names of its own
 * objects against its own imagesDirFor(path), made absolute as each object is
 * read (resolveExternalImages). MRPT's process-wide CImage images path is
 * neither used nor changed, so two readers open at once (a survey and a live
 * rawlog) never look up each other's images. */
class RawlogReader
{
   public:
	/** Opens the file. Throws RawlogError. */
	explicit RawlogReader(const std::string& path);
	~RawlogReader();
	RawlogReader(const RawlogReader&) = delete;
	RawlogReader& operator=(const RawlogReader&) = delete;

	/** The next object, or nullptr at a clean end of file (every byte read
	 * and, for gzip, the trailer checked); its observations' external image
	 * names are absolute paths in imagesDir(). Throws RawlogError on an
	 * unregistered class, a truncated or corrupt object, a length field
	 * larger than what remains, a gzip stream without or with a wrong trailer. */
	mrpt::serialization::CSerializable::Ptr next();

	/** Absolute imagesDirFor(path()): where relative image names resolve. */
	const std::string& imagesDir() const { return m_imagesDir; }

	/** Index (0-based) of the object last returned by next(). */
	size_t index() const { return m_count == 0 ? 0 : m_count - 1; }
	/** Fraction of the (compressed) file consumed, in [0,1]. */
	double progress() const;
	const std::string& path() const { return m_path; }

	/** "<path>: object #<index>: <what>", for errors about the last object. */
	std::string where(const std::string& what) const;

   private:
	std::string m_path, m_imagesDir;
	std::unique_ptr<detail::CheckedInputStream> m_in;
	size_t m_count = 0;
};

/** Observations carried by a top-level rawlog object: the object itself if it
 * is an observation, the members of a sensory frame, none for actions. */
std::vector<mrpt::obs::CObservation::Ptr> observationsIn(
	const mrpt::serialization::CSerializable::Ptr& obj);

/** Rewrites every relative external image name of a camera observation
 * (stereo: left, right, disparity; single image) to an absolute path in
 * `imagesDir`; absolute names and inline images are left alone. */
void resolveExternalImages(mrpt::obs::CObservation& obs, const std::string& imagesDir);

/** Loads every image an observation stores externally, so a missing file
 * shows up here (with its path) rather than deep inside a filter. Each file
 * is checked first (io::checkImageFile): a truncated one is an error. */
void loadExternalImages(mrpt::obs::CObservation& obs);

/** " (left image 'f', right image 'g')" for the images an observation
 * stores externally, "" if it stores none: for messages about its images. */
std::string externalImagesOf(const mrpt::obs::CObservation& obs);

/** Writes a rawlog to a temporary sibling and renames it into place on
 * commit(). Without commit() (an exception, an early return) the temporary
 * file and images are deleted: no half-written output is ever left behind.
 * The rawlog and its images folder are outputs of an OutputTransaction: the
 * writer's own, or the command's (then they are put in place together with
 * the command's other outputs, by the transaction's commit()). */
class RawlogWriter
{
   public:
	/** externalImages: write images given to externalise() as PNG files in
	 * imagesDirFor(path) (staged in a temporary folder until commit()).
	 * tx: the command's transaction (which must outlive the writer), or
	 * nullptr for one of the writer's own. Throws RawlogError if the output
	 * cannot be reserved (missing directory, an input of tx, ...). */
	explicit RawlogWriter(const std::string& path, bool externalImages = false, OutputTransaction* tx = nullptr);
	~RawlogWriter();
	RawlogWriter(const RawlogWriter&) = delete;
	RawlogWriter& operator=(const RawlogWriter&) = delete;

	void write(const mrpt::serialization::CSerializable& obj);
	size_t written() const { return m_written; }

	/** When external images are on: saves img as PNG under `name` (relative
	 * to the images directory) and turns it into an external reference. */
	void externalise(mrpt::img::CImage& img, const std::string& name);
	bool externalImages() const { return m_externalImages; }

	/** For an image an input rawlog stores externally (relative to
	 * sourceImagesDir) and that is written out unchanged: links (or copies)
	 * its file into this rawlog's images folder under the same name, so that
	 * the output does not point at files that are not beside it; a name the
	 * reader made absolute inside sourceImagesDir becomes relative again.
	 * Images stored inline or elsewhere need nothing. */
	void carryExternalImage(mrpt::img::CImage& img, const std::string& sourceImagesDir);

	/** Flushes and closes; with the writer's own transaction, also renames
	 * into place (replacing an old file). With the command's transaction,
	 * its commit() does that. */
	void commit();

	const std::string& path() const { return m_path; }

   private:
	/** The staged images folder, reserved in the transaction on first use. */
	const std::string& stagedImagesDir();

	std::string m_path, m_tmpPath, m_imagesDir, m_tmpImagesDir;
	bool m_externalImages = false;
	bool m_committed = false;
	size_t m_written = 0;
	std::unique_ptr<OutputTransaction> m_ownTx;
	OutputTransaction* m_tx = nullptr;
	std::unique_ptr<mrpt::io::CFileGZOutputStream> m_out;
};

}  // namespace shadyloc::io
