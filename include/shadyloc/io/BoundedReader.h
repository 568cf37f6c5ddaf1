/* ShadyLoc — bounded reading of our binary formats (MRPT CArchive): every
 * count or length read from a stream is checked against the bytes that can
 * still be there before anything is allocated, so a corrupt or hostile file
 * gives an error naming the object and the byte offset, never a huge
 * allocation. Used by every reader of ours (filters' serializeFrom, keyframes,
 * the map). */
#pragma once

#include <mrpt/serialization/CArchive.h>

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace mrpt::io
{
class CStream;
}

namespace shadyloc::io
{
/** A persistent object that cannot be what it claims: truncated, a count or
 * length beyond the remaining bytes, an unknown version, an impossible value.
 * The message names the object and the byte offset. */
class CorruptDataError : public std::runtime_error
{
   public:
	using std::runtime_error::runtime_error;
};

/** Reads fields from an archive while counting bytes against a budget.
 *
 * The budget is what can still be in the stream: for a file or memory stream,
 * its size minus its position (remainingBytes()); where the size is not
 * known (a gz stream, inside CSerializable::serializeFrom, a pipe) a bound the
 * caller gives (the largest the object can plausibly be). Every read goes
 * through this class, so offset() is exact: relative to `baseOffset`, which is
 * the stream position at the start when known (absolute file offsets in
 * messages) and 0 otherwise (offsets within the object's data). */
class BoundedReader
{
   public:
	/** `what` names the object in errors ("keyframe 12", "shadyloc::CFilterInvariant"). */
	BoundedReader(
		mrpt::serialization::CArchive& in, std::string what, uint64_t budgetBytes,
		uint64_t baseOffset = 0);

	/** Bytes left in `s` (size - position) for streams that know their size
	 * exactly (mrpt::io::CMemoryStream, CFileInputStream, CFileStream);
	 * `fallback` for any other (gz streams report the compressed size). */
	static uint64_t remainingBytes(const mrpt::io::CStream& s, uint64_t fallback);
	/** The stream position for streams that know it exactly, else 0. */
	static uint64_t positionOf(const mrpt::io::CStream& s);

	/** One arithmetic value (or bool: 1 byte) in MRPT's little-endian layout. */
	template <class T>
	void read(T& v, const char* field)
	{
		static_assert(std::is_arithmetic_v<T>, "read(): arithmetic types only");
		if constexpr (std::is_same_v<T, bool>)
		{
			uint8_t b = 0;
			read(b, field);
			v = b != 0;
		}
		else
		{
			// Not `m_in >> v`: MRPT accepts a short read there silently.
			start(sizeof(T), field);
			size_t got = 0;
			guarded(field, [&] { got = m_in.ReadBufferFixEndianness(&v, 1); });
			finish(got, sizeof(T), field);
		}
	}
	template <class T>
	T read(const char* field)
	{
		T v{};
		read(v, field);
		return v;
	}

	/** A fixed-size Eigen matrix of doubles/floats, row by row. */
	template <class Derived>
	void readMatrix(Eigen::MatrixBase<Derived>& M, const char* field)
	{
		using S = typename Derived::Scalar;
		start(sizeof(S) * static_cast<uint64_t>(M.size()), field);
		for (Eigen::Index i = 0; i < M.rows(); i++)
			for (Eigen::Index j = 0; j < M.cols(); j++) read(M(i, j), field);
	}

	/** Raw bytes. */
	void readBytes(void* dst, size_t n, const char* field);

	/** A uint32 count of items that each take at least `minItemBytes` on disk;
	 * throws if that many cannot fit in the remaining bytes or exceed
	 * `maxCount`. Check before resize(), then read the items. */
	size_t readCount(const char* field, size_t minItemBytes, size_t maxCount = std::numeric_limits<uint32_t>::max());

	/** A string in MRPT's layout (uint32 length, then the bytes: what
	 * `CArchive << std::string` writes), at most `maxLength` bytes. */
	void readString(std::string& s, const char* field, size_t maxLength);

	/** Throws CorruptDataError "<what>: byte <offset>: <field>: <message>",
	 * offset being where the field being read (or last read) starts. */
	[[noreturn]] void fail(const char* field, const std::string& message) const;

	uint64_t offset() const { return m_base + m_used; }	 //!< of the next byte to read
	uint64_t remaining() const { return m_budget - m_used; }  //!< bytes the budget still allows
	uint64_t used() const { return m_used; }  //!< bytes read so far
	const std::string& what() const { return m_what; }
	mrpt::serialization::CArchive& archive() { return m_in; }

   private:
	/** Marks the start of a field of n bytes; throws unless they fit in the budget. */
	void start(uint64_t n, const char* field);
	/** Counts a read of `want` bytes that returned `got`; throws if short. */
	void finish(size_t got, size_t want, const char* field);
	/** Runs a read, turning the stream's own errors (end of file) into ours. */
	template <class F>
	void guarded(const char* field, F&& f)
	{
		try
		{
			f();
		}
		catch (const std::exception& e)
		{
			fail(field, std::string("truncated or unreadable (") + firstLine(e.what()) + ")");
		}
	}
	static std::string firstLine(const std::string& s);

	mrpt::serialization::CArchive& m_in;
	std::string m_what;
	uint64_t m_budget, m_base, m_used = 0;
	uint64_t m_fieldStart = 0;	//!< offset() where the current field started
};

}  // namespace shadyloc::io
