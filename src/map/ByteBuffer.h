/* ShadyLoc — little-endian byte buffers for the keyframe map's blocks: a
 * writer, and a bounded reader whose every read checks the remaining bytes
 * and names the object and offset on failure (never a huge allocation from a
 * damaged count). Private to src/map.
 *
 * The map's blocks are decompressed into memory first, so their exact size is
 * known: ByteReader applies io::BoundedReader's rules to such a buffer (every
 * read checked against the bytes left, a count checked by requireItems()
 * before anything is sized by it, errors io::CorruptDataError naming the
 * object and byte offset) with a memcpy per value instead of a virtual stream
 * call: a map holds millions of values. */
#pragma once

#include <shadyloc/io/BoundedReader.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace shadyloc::map::detail
{
static_assert(
	__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the map format is little-endian; add byte swaps for this CPU");

class ByteWriter
{
   public:
	std::vector<uint8_t> buf;

	template <typename T>
	void put(T v)
	{
		static_assert(std::is_arithmetic_v<T>);
		const size_t n = buf.size();
		buf.resize(n + sizeof(T));
		std::memcpy(buf.data() + n, &v, sizeof(T));
	}
	void bytes(const void* p, size_t n)
	{
		const auto* b = static_cast<const uint8_t*>(p);
		buf.insert(buf.end(), b, b + n);
	}
	/** Length-prefixed (u16) string. */
	void str(const std::string& s)
	{
		if (s.size() > 65535) throw std::length_error("string too long to store: " + s.substr(0, 40) + "...");
		put(static_cast<uint16_t>(s.size()));
		bytes(s.data(), s.size());
	}
};

class ByteReader
{
   public:
	/** what: names the object being read, for error messages. */
	ByteReader(const uint8_t* data, size_t size, std::string what) : m_p(data), m_n(size), m_what(std::move(what))
	{
	}

	template <typename T>
	T get()
	{
		static_assert(std::is_arithmetic_v<T>);
		need(sizeof(T), "value");
		T v;
		std::memcpy(&v, m_p + m_off, sizeof(T));
		m_off += sizeof(T);
		return v;
	}
	void bytes(void* out, size_t n)
	{
		need(n, "bytes");
		std::memcpy(out, m_p + m_off, n);
		m_off += n;
	}
	std::string str()
	{
		const auto n = get<uint16_t>();
		need(n, "string");
		std::string s(reinterpret_cast<const char*>(m_p + m_off), n);
		m_off += n;
		return s;
	}
	/** Throws unless count items of itemBytes each can still follow. */
	void requireItems(uint64_t count, size_t itemBytes, const char* what) const
	{
		if (itemBytes && count > (m_n - m_off) / itemBytes)
			fail(
				std::string(what) + " count " + std::to_string(count) + " needs more than the " +
				std::to_string(m_n - m_off) + " bytes left");
	}
	[[noreturn]] void fail(const std::string& msg) const
	{
		throw io::CorruptDataError(m_what + ": byte " + std::to_string(m_off) + ": " + msg);
	}
	size_t offset() const { return m_off; }
	size_t remaining() const { return m_n - m_off; }

   private:
	void need(size_t k, const char* what) const
	{
		if (k > m_n - m_off)
			fail(
				std::string("truncated: ") + what + " of " + std::to_string(k) + " bytes, " +
				std::to_string(m_n - m_off) + " left");
	}
	const uint8_t* m_p;
	size_t m_n;
	size_t m_off = 0;
	std::string m_what;
};

}  // namespace shadyloc::map::detail
