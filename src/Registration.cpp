/* ShadyLoc — the one list of the MRPT classes, and their registration when
 * the library loads (include/shadyloc/Registration.h). Add new classes here. */
#include <shadyloc/Registration.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <mrpt/rtti/CObject.h>

void shadyloc::registerAllClasses()
{
	using namespace mrpt::rtti;
	registerClass(CLASS_ID(shadyloc::CObservationFilter));
	registerClass(CLASS_ID(shadyloc::CFilterMonochrome));
	registerClass(CLASS_ID(shadyloc::CFilterInvariant));
	registerClass(CLASS_ID(shadyloc::CFilterLinearise));
	registerClass(CLASS_ID(shadyloc::CKeyframeMap));
}

namespace
{
/** At load time. A static object, not MRPT_INITIALIZER, and this file is
 * linked last (CMakeLists.txt): a class id holds a std::function, so it is
 * initialised dynamically, in the file that defines it, and a library's
 * files are initialised in link order; registering before the ids are set
 * registers nothing. FormatsRegistry.ClassesAreRegisteredWhenTheLibraryLoads
 * checks it. */
struct TRegisterAtLoad
{
	TRegisterAtLoad() { shadyloc::registerAllClasses(); }
} registerAtLoad;
}  // namespace
