/* ShadyLoc — the byte stream under RawlogReader (private to the library).
 *
 * Reads a plain or gzip-compressed file through zlib's inflate directly, so
 * that the end of the data is known exactly: a gzip stream must end with its
 * trailer (CRC-32 and length, both checked by inflate), and a read that
 * cannot be served in full is an error, never a short read (MRPT ignores the
 * count of some reads, which let a rawlog cut inside its last object pass as
 * complete). Decompressed bytes are kept in a buffer that can be filled ahead
 * on request: hasAtLeast(n) answers whether n more bytes exist, which bounds
 * every length field by what remains in the stream.
 */
#pragma once

#include <mrpt/io/CStream.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace shadyloc::io::detail
{
class CheckedInputStream : public mrpt::io::CStream
{
   public:
	/** Opens `path` (gzip or plain, told by its first two bytes). Throws
	 * RawlogError naming the file. */
	explicit CheckedInputStream(const std::string& path);
	~CheckedInputStream() override;
	CheckedInputStream(const CheckedInputStream&) = delete;
	CheckedInputStream& operator=(const CheckedInputStream&) = delete;

	/** Exactly n bytes, or throws RawlogError (and failure() says why). */
	size_t Read(void* buf, size_t n) override;
	size_t Write(const void*, size_t) override;
	uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override;
	/** Size of the file on disk [bytes]. */
	uint64_t getTotalBytesCount() const override { return m_fileSize; }
	/** Position in the decompressed data [bytes]. */
	uint64_t getPosition() const override { return m_consumed; }

	/** Bytes of the file read so far (compressed, for progress). */
	uint64_t filePosition() const { return m_filePos; }

	/** True if at least n more decompressed bytes exist (decompresses ahead
	 * as far as needed, never further than the data). Throws RawlogError on
	 * a damaged stream (bad CRC, missing trailer, corrupt deflate data). */
	bool hasAtLeast(size_t n);

	/** True at a clean end: no byte left and, for gzip, every member ended
	 * with a matching trailer. Throws RawlogError on a damaged end. */
	bool atCleanEnd() { return !hasAtLeast(1); }

	/** Why the last Read() or fill failed ("" if none). */
	const std::string& failure() const { return m_failure; }
	void clearFailure() { m_failure.clear(); }

	bool compressed() const { return m_gzip; }

   private:
	/** Appends decompressed bytes to the buffer; false at the end of data. */
	bool fill();
	/** Just after the class name of an mrpt::img::CImage was read: checks the
	 * sizes its header announces before MRPT reads them (see the .cpp). */
	void checkImageHeaderAhead();
	uint32_t peek32(size_t offset) const;
	[[noreturn]] void fail(const std::string& why);
	void compact();

	std::string m_path;
	std::FILE* m_file = nullptr;
	uint64_t m_fileSize = 0, m_filePos = 0, m_consumed = 0;
	bool m_gzip = false, m_fileEnded = false, m_dataEnded = false;
	bool m_memberOpen = false;	//!< inside a gzip member (trailer not yet seen)
	struct Zlib;
	std::unique_ptr<Zlib> m_z;
	std::vector<uint8_t> m_in;	 //!< compressed input not yet inflated
	size_t m_inPos = 0, m_inEnd = 0;
	std::vector<uint8_t> m_buf;	 //!< decompressed bytes [m_pos, m_end) not yet read
	size_t m_pos = 0, m_end = 0;
	std::string m_failure;
	uint8_t m_prevLast = 0;	 //!< last byte of the previous Read() (a class name's length byte)
};

}  // namespace shadyloc::io::detail
