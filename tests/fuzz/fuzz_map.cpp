/* Fuzz target: the keyframe map loader (CKeyframeMap::LoadFromBytes, what
 * LoadFromFile does after reading the file). Every input must give a map or
 * an exception whose message names the source; never a crash, a sanitizer
 * report or an allocation beyond libFuzzer's -malloc_limit_mb. */
#include "FuzzSupport.h"

#include <shadyloc/core/Registration.h>
#include <shadyloc/map/CKeyframeMap.h>

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
	shadyloc::registerAllClasses();
	return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	if (size > 4 * 1024 * 1024) return 0;
	const std::string name = "fuzz.kfmap";
	try
	{
		const auto m = shadyloc::CKeyframeMap::LoadFromBytes(data, size, name);
		if (!m) shadyloc::fuzz::contractViolated("LoadFromBytes", "returned null without an error");
		(void)m->asString();
	}
	catch (const std::exception& e)
	{
		if (std::string(e.what()).find(name) == std::string::npos)
			shadyloc::fuzz::contractViolated("map load error does not name the source", e.what());
	}
	return 0;
}
