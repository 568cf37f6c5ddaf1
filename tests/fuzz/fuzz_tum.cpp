/* Fuzz target: the TUM trajectory reader (io::readTum). Every input
 * must give poses or a std::runtime_error naming the file. */
#include "FuzzSupport.h"

#include <shadyloc/io/Tum.h>

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	if (size > 256 * 1024) return 0;
	const std::string& path = shadyloc::fuzz::scratchPath("tum");
	shadyloc::fuzz::writeScratch(path, data, size);
	try
	{
		for (const auto& p : shadyloc::io::readTum(path))
			if (!std::isfinite(p.t) || !std::isfinite(p.T.translation().x()))
				shadyloc::fuzz::contractViolated("readTum", "returned a non-finite pose");
	}
	catch (const std::runtime_error& e)
	{
		if (std::string(e.what()).find(path) == std::string::npos)
			shadyloc::fuzz::contractViolated("readTum error does not name the file", e.what());
	}
	return 0;
}
