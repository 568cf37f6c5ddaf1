/* ShadyLoc fuzz targets: shared helpers (libFuzzer, see tests/fuzz/README.md). */
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <unistd.h>

namespace shadyloc::fuzz
{
/** A per-process scratch file the readers that take a path read the input
 * from (in /dev/shm when there is one: no disk traffic). */
inline const std::string& scratchPath(const char* name)
{
	static const std::string p = [name] {
		const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
		return std::string(dir) + "/shadyloc_fuzz_" + name + "_" + std::to_string(getpid());
	}();
	return p;
}

inline void writeScratch(const std::string& path, const uint8_t* data, size_t size)
{
	std::FILE* f = std::fopen(path.c_str(), "wb");
	if (!f) std::abort();
	if (size && std::fwrite(data, 1, size, f) != size) std::abort();
	std::fclose(f);
}

/** A finding: the code under test broke its own contract (not a crash the
 * sanitizers would see on their own). */
[[noreturn]] inline void contractViolated(const char* what, const char* detail)
{
	std::fprintf(stderr, "contract violated: %s: %s\n", what, detail);
	std::abort();
}

}  // namespace shadyloc::fuzz
