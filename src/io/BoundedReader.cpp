/* ShadyLoc — bounded reading of our binary formats. */
#include <shadyloc/io/BoundedReader.h>

#include <mrpt/io/CFileInputStream.h>
#include <mrpt/io/CFileStream.h>
#include <mrpt/io/CMemoryStream.h>

namespace shadyloc::io
{
BoundedReader::BoundedReader(
	mrpt::serialization::CArchive& in, std::string what, uint64_t budgetBytes, uint64_t baseOffset)
	: m_in(in), m_what(std::move(what)), m_budget(budgetBytes), m_base(baseOffset), m_fieldStart(baseOffset)
{
}

namespace
{
/** Streams whose getTotalBytesCount() is the exact number of readable bytes. */
bool knowsItsSize(const mrpt::io::CStream& s)
{
	return dynamic_cast<const mrpt::io::CMemoryStream*>(&s) ||
		   dynamic_cast<const mrpt::io::CFileInputStream*>(&s) ||
		   dynamic_cast<const mrpt::io::CFileStream*>(&s);
}
}  // namespace

uint64_t BoundedReader::remainingBytes(const mrpt::io::CStream& s, uint64_t fallback)
{
	if (!knowsItsSize(s)) return fallback;
	const uint64_t total = s.getTotalBytesCount(), pos = s.getPosition();
	return pos <= total ? total - pos : 0;
}

uint64_t BoundedReader::positionOf(const mrpt::io::CStream& s)
{
	return knowsItsSize(s) ? s.getPosition() : 0;
}

void BoundedReader::start(uint64_t n, const char* field)
{
	m_fieldStart = offset();
	if (n > remaining())
		fail(
			field, "needs " + std::to_string(n) + " bytes, only " + std::to_string(remaining()) +
					   " can remain (truncated or corrupt)");
}

void BoundedReader::finish(size_t got, size_t want, const char* field)
{
	if (got != want)
		fail(field, "truncated: " + std::to_string(got) + " of " + std::to_string(want) + " bytes");
	m_used += want;
}

void BoundedReader::readBytes(void* dst, size_t n, const char* field)
{
	start(n, field);
	if (n == 0) return;
	size_t got = 0;
	guarded(field, [&] { got = m_in.ReadBuffer(dst, n); });
	finish(got, n, field);
}

size_t BoundedReader::readCount(const char* field, size_t minItemBytes, size_t maxCount)
{
	const uint64_t at = offset();
	const uint32_t n = read<uint32_t>(field);
	auto bad = [&](const std::string& msg) {
		throw CorruptDataError(
			m_what + ": byte " + std::to_string(at) + ": " + field + ": count " + std::to_string(n) +
			" " + msg);
	};
	if (n > maxCount) bad("exceeds the largest allowed, " + std::to_string(maxCount));
	if (minItemBytes > 0 && static_cast<uint64_t>(n) > remaining() / minItemBytes)
		bad("needs at least " + std::to_string(static_cast<uint64_t>(n) * minItemBytes) +
			" bytes, only " + std::to_string(remaining()) + " can remain (truncated or corrupt)");
	return n;
}

void BoundedReader::readString(std::string& s, const char* field, size_t maxLength)
{
	const size_t n = readCount(field, 1, maxLength);
	s.assign(n, '\0');
	if (n) readBytes(s.data(), n, field);
}

void BoundedReader::fail(const char* field, const std::string& message) const
{
	throw CorruptDataError(
		m_what + ": byte " + std::to_string(m_fieldStart) + ": " + field + ": " + message);
}

std::string BoundedReader::firstLine(const std::string& s)
{
	// MRPT exceptions carry a multi-line call trace; the first line says what.
	const auto nl = s.find('\n');
	return nl == std::string::npos ? s : s.substr(0, nl);
}

}  // namespace shadyloc::io
