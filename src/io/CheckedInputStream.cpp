/* ShadyLoc — checked plain/gzip input stream (see CheckedInputStream.h). */
#include "CheckedInputStream.h"

#include <shadyloc/io/AllocationBound.h>
#include <shadyloc/io/Rawlog.h>

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

namespace shadyloc::io::detail
{
namespace
{
constexpr size_t kInChunk = 64 * 1024;	//!< compressed bytes read per fread
constexpr size_t kOutChunk = 256 * 1024;  //!< decompressed bytes added per fill
}  // namespace

struct CheckedInputStream::Zlib
{
	z_stream z{};
	bool initialised = false;
	~Zlib()
	{
		if (initialised) inflateEnd(&z);
	}
};

CheckedInputStream::CheckedInputStream(const std::string& path) : m_path(path)
{
	std::error_code ec;
	if (!std::filesystem::is_regular_file(path, ec))
		throw RawlogError("'" + path + "': no such rawlog file");
	m_fileSize = std::filesystem::file_size(path, ec);
	m_file = std::fopen(path.c_str(), "rb");
	if (!m_file) throw RawlogError("'" + path + "': cannot open: " + std::strerror(errno));
	m_in.resize(kInChunk);
	m_inEnd = std::fread(m_in.data(), 1, m_in.size(), m_file);
	m_filePos = m_inEnd;
	m_fileEnded = m_inEnd < m_in.size();
	m_gzip = m_inEnd >= 2 && m_in[0] == 0x1f && m_in[1] == 0x8b;
	if (m_gzip)
	{
		m_z = std::make_unique<Zlib>();
		// 15 + 16: gzip wrapper only (its trailer is checked by inflate).
		if (inflateInit2(&m_z->z, 15 + 16) != Z_OK)
		{
			std::fclose(m_file);
			throw RawlogError("'" + path + "': cannot start the gzip decoder");
		}
		m_z->initialised = true;
		m_memberOpen = true;
	}
}

CheckedInputStream::~CheckedInputStream()
{
	if (m_file) std::fclose(m_file);
}

size_t CheckedInputStream::Write(const void*, size_t)
{
	throw RawlogError("'" + m_path + "': the rawlog reader cannot write");
}

uint64_t CheckedInputStream::Seek(int64_t, mrpt::io::CStream::TSeekOrigin)
{
	throw RawlogError("'" + m_path + "': the rawlog reader reads forward only");
}

void CheckedInputStream::fail(const std::string& why)
{
	m_failure = why;
	throw RawlogError("'" + m_path + "': " + why);
}

void CheckedInputStream::compact()
{
	if (m_pos == 0) return;
	std::memmove(m_buf.data(), m_buf.data() + m_pos, m_end - m_pos);
	m_end -= m_pos;
	m_pos = 0;
}

bool CheckedInputStream::fill()
{
	if (m_dataEnded) return false;
	const AllocationBound::Pause unchecked;	 // the buffer grows only with real data
	compact();
	// Room for one more chunk (the buffer only grows as far as asked for).
	if (m_buf.size() - m_end < kOutChunk) m_buf.resize(m_end + kOutChunk);

	auto refillInput = [&]() {
		if (m_inPos < m_inEnd || m_fileEnded) return;
		m_inPos = 0;
		m_inEnd = std::fread(m_in.data(), 1, m_in.size(), m_file);
		m_filePos += m_inEnd;
		if (m_inEnd == 0)
		{
			if (std::ferror(m_file)) fail(std::string("read error: ") + std::strerror(errno));
			m_fileEnded = true;
		}
	};

	if (!m_gzip)
	{
		// Plain file: what is in the input buffer first, then straight reads.
		size_t got = 0;
		if (m_inPos < m_inEnd)
		{
			got = std::min(m_inEnd - m_inPos, m_buf.size() - m_end);
			std::memcpy(m_buf.data() + m_end, m_in.data() + m_inPos, got);
			m_inPos += got;
		}
		else if (!m_fileEnded)
		{
			got = std::fread(m_buf.data() + m_end, 1, m_buf.size() - m_end, m_file);
			m_filePos += got;
			if (got == 0)
			{
				if (std::ferror(m_file)) fail(std::string("read error: ") + std::strerror(errno));
				m_fileEnded = true;
			}
		}
		m_end += got;
		if (got == 0) m_dataEnded = true;
		return got > 0;
	}

	auto& z = m_z->z;
	const size_t before = m_end;
	while (m_end == before)
	{
		if (!m_memberOpen)
		{
			// After a member's trailer: another member may follow (gzip
			// allows concatenation); anything else is damage.
			refillInput();
			if (m_inPos == m_inEnd)
			{
				m_dataEnded = true;
				return false;
			}
			if (m_in[m_inPos] != 0x1f)
				fail("unexpected bytes after the end of the compressed data (damaged file?)");
			inflateReset(&z);
			m_memberOpen = true;
		}
		refillInput();
		if (m_inPos == m_inEnd)
			fail("the compressed data ends without its gzip trailer (file truncated?)");
		z.next_in = m_in.data() + m_inPos;
		z.avail_in = static_cast<uInt>(m_inEnd - m_inPos);
		z.next_out = m_buf.data() + m_end;
		z.avail_out = static_cast<uInt>(m_buf.size() - m_end);
		const int rc = inflate(&z, Z_NO_FLUSH);
		m_inPos = m_inEnd - z.avail_in;
		m_end = m_buf.size() - z.avail_out;
		if (rc == Z_STREAM_END)
			m_memberOpen = false;  // trailer read and its CRC-32 and length matched
		else if (rc == Z_DATA_ERROR)
			fail(std::string("corrupt compressed data (") + (z.msg ? z.msg : "invalid deflate stream") + ")");
		else if (rc == Z_MEM_ERROR)
			fail("out of memory while decompressing");
		else if (rc != Z_OK && rc != Z_BUF_ERROR)
			fail("gzip decoder error " + std::to_string(rc));
	}
	return true;
}

bool CheckedInputStream::hasAtLeast(size_t n)
{
	while (m_end - m_pos < n)
		if (!fill()) return false;
	return true;
}

size_t CheckedInputStream::Read(void* buf, size_t n)
{
	if (n == 0) return 0;
	if (!hasAtLeast(n))
		fail(
			"truncated: the data ends in the middle of an object (" + std::to_string(m_end - m_pos) +
			" of " + std::to_string(n) + " bytes left for one field)");
	std::memcpy(buf, m_buf.data() + m_pos, n);
	m_pos += n;
	m_consumed += n;
	// An object header is the name's length byte (0x80 | length), then the name.
	static constexpr char kImageClass[] = "mrpt::img::CImage";
	constexpr size_t kLen = sizeof(kImageClass) - 1;
	const bool imageHeader = n == kLen && m_prevLast == (0x80 | kLen) && std::memcmp(buf, kImageClass, n) == 0;
	m_prevLast = static_cast<const uint8_t*>(buf)[n - 1];
	if (imageHeader) checkImageHeaderAhead();
	return n;
}

uint32_t CheckedInputStream::peek32(size_t offset) const
{
	const uint8_t* p = m_buf.data() + m_pos + offset;  // MRPT archives are little-endian
	return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

void CheckedInputStream::checkImageHeaderAhead()
{
	// Most lengths MRPT reads are bounded by the allocation bound (operator
	// new, cv::Mat). Two in CImage's format are not: a JPEG-compressed image
	// (versions 1..9) goes into a CMemoryStream sized with realloc() from its
	// byte count, and version 0 copies a stored byte count into a pixel
	// buffer sized from width x height x channels without comparing the two.
	// Both fields sit at fixed offsets after the version byte, so they are
	// checked here, ahead of MRPT, against what the stream still holds.
	if (!hasAtLeast(1)) return;	 // the truncation shows up at the next read
	const uint8_t version = m_buf[m_pos];
	auto announce = [&](uint64_t bytes, size_t dataAt) {
		if (!hasAtLeast(dataAt)) return;
		if (!hasAtLeast(dataAt + bytes))
			fail(
				"corrupt data: an image announces " + std::to_string(bytes) + " bytes, more than remain in the file");
	};
	if (version == 0)
	{
		if (!hasAtLeast(18)) return;
		const uint64_t w = peek32(1), h = peek32(5), c = peek32(9);
		const uint64_t len = peek32(14);
		if (len > w * h * c) fail("corrupt data: an image stores " + std::to_string(len) + " bytes for " +
								  std::to_string(w) + "x" + std::to_string(h) + "x" + std::to_string(c) + " pixels");
		announce(len, 18);
	}
	else if (version == 1)
	{
		if (hasAtLeast(5)) announce(peek32(1), 5);
	}
	else if (version <= 9)
	{
		size_t at = 1;
		if (version >= 6)
		{
			if (!hasAtLeast(at + 1) || m_buf[m_pos + at] != 0) return;	// stored externally: a file name
			at++;
		}
		if (!hasAtLeast(at + 1) || m_buf[m_pos + at] == 0) return;	// grey: raw bytes, sized by cv::Mat
		at++;
		if (version >= 7)
		{
			if (!hasAtLeast(at + 8)) return;
			const int32_t w = static_cast<int32_t>(peek32(at)), h = static_cast<int32_t>(peek32(at + 4));
			if (!(w >= 1 && h >= 1)) return;	 // raw colour: sized by cv::Mat
			at += 8;
		}
		if (hasAtLeast(at + 4)) announce(peek32(at), at + 4);
	}
}

}  // namespace shadyloc::io::detail
