/* Fuzz target: the checked rawlog reader (io::RawlogReader). Every input must
 * read to a clean end or fail with io::RawlogError; no crash, no sanitizer
 * report, no allocation beyond libFuzzer's -malloc_limit_mb (the length
 * bound; built without it, fuzz_rawlog_nobound shows the target reaches it). */
#include "FuzzSupport.h"

#include <shadyloc/Registration.h>
#include <shadyloc/io/Rawlog.h>

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
	shadyloc::registerAllClasses();
	return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	const std::string& path = shadyloc::fuzz::scratchPath("rawlog");
	shadyloc::fuzz::writeScratch(path, data, size);
	try
	{
		shadyloc::io::RawlogReader reader(path);
		while (const auto obj = reader.next())
			for (const auto& o : shadyloc::io::observationsIn(obj)) (void)o->sensorLabel.size();
	}
	catch (const shadyloc::io::RawlogError&)
	{
		// a clear error: what we want
	}
	catch (const std::exception& e)
	{
		shadyloc::fuzz::contractViolated("RawlogReader threw something other than RawlogError", e.what());
	}
	return 0;
}
