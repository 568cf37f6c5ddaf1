/* ShadyLoc — the one list of the MRPT classes (include/shadyloc/Registration.h).
 * Add new classes here, and register them at load time in their own file. */
#include <shadyloc/Registration.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <mrpt/rtti/CObject.h>

// Why each class also registers itself, in its own file, when the library
// loads: a class id holds a std::function, so it may be initialised
// dynamically, in the file that defines it; the order of files is fixed by no
// rule a build keeps (a unity build links its batches in reverse, and g++
// happens to initialise the ids statically where clang does not). Only within
// one file does the language fix the order. This list is for the programs and
// the plugin, which call it after loading (idempotent);
// FormatsRegistry.ClassesAreRegisteredWhenTheLibraryLoads checks the load-time
// registrations in a process that calls nothing.
void shadyloc::registerAllClasses()
{
	using namespace mrpt::rtti;
	registerClass(CLASS_ID(shadyloc::CObservationFilter));
	registerClass(CLASS_ID(shadyloc::CFilterMonochrome));
	registerClass(CLASS_ID(shadyloc::CFilterInvariant));
	registerClass(CLASS_ID(shadyloc::CFilterLinearise));
	registerClass(CLASS_ID(shadyloc::CKeyframeMap));
}
