/* Fuzz target: the keyframe map loader, both ways in: LoadFromFile (the
 * file checks: a regular file, its size bounded, the MRPT object header
 * checked on the first bytes before the rest is read) on a scratch file
 * holding the input, and LoadFromBytes (the parse). Every input must give a
 * map or an exception whose message names the source, and both ways must
 * agree; never a crash, a sanitizer report or an allocation beyond
 * libFuzzer's -malloc_limit_mb. */
#include "FuzzSupport.h"

#include <shadyloc/Registration.h>
#include <shadyloc/map/CKeyframeMap.h>

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
	shadyloc::registerAllClasses();
	return 0;
}

namespace
{
/** True if a map loads; an error must name `name`. */
template <class Load>
bool loads(const std::string& name, Load&& load)
{
	try
	{
		const auto m = load();
		if (!m) shadyloc::fuzz::contractViolated("map load", "returned null without an error");
		(void)m->asString();
		return true;
	}
	catch (const std::exception& e)
	{
		if (std::string(e.what()).find(name) == std::string::npos)
			shadyloc::fuzz::contractViolated("map load error does not name the source", e.what());
		return false;
	}
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	if (size > 4 * 1024 * 1024) return 0;
	const std::string name = "fuzz.kfmap";
	const bool fromBytes = loads(name, [&] { return shadyloc::CKeyframeMap::LoadFromBytes(data, size, name); });
	// The file path: the header-first check and the reads bounded by the size.
	const std::string& file = shadyloc::fuzz::scratchPath("map");
	shadyloc::fuzz::writeScratch(file, data, size);
	const bool fromFile = loads(file, [&] { return shadyloc::CKeyframeMap::LoadFromFile(file); });
	if (fromBytes != fromFile)
		shadyloc::fuzz::contractViolated("map load", fromFile ? "the file loads, its bytes do not" : "the bytes load, the file does not");
	return 0;
}
