/* ShadyLoc — FNV-1a 64 of files and texts (FileHash.h). */
#include <shadyloc/io/FileHash.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace shadyloc::io
{
namespace
{
constexpr uint64_t kOffsetBasis = 1469598103934665603ull, kPrime = 1099511628211ull;

void add(uint64_t& h, const char* bytes, size_t n)
{
	for (size_t i = 0; i < n; i++)
	{
		h ^= static_cast<uint8_t>(bytes[i]);
		h *= kPrime;
	}
}

std::string hex64(uint64_t h)
{
	char s[17];
	std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
	return s;
}
}  // namespace

std::string fnv1a64File(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw std::runtime_error("cannot read '" + path + "'");
	uint64_t h = kOffsetBasis;
	std::vector<char> buf(1 << 16);
	while (f)
	{
		f.read(buf.data(), static_cast<std::streamsize>(buf.size()));
		add(h, buf.data(), static_cast<size_t>(f.gcount()));
	}
	return hex64(h);
}

std::string fnv1a64(const std::string& text)
{
	uint64_t h = kOffsetBasis;
	add(h, text.data(), text.size());
	return hex64(h);
}

}  // namespace shadyloc::io
