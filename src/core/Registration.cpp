/* ShadyLoc — one place that registers every class (like MRPT's
 * registerAllClasses.cpp per library). Add new classes here. */
#include <shadyloc/core/Registration.h>
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

// At load time each class is registered by a static object in the file that
// defines it, after its class id is initialised (the ids are initialised
// dynamically, in an order across files the compiler chooses; clang ran an
// initializer here first, which registered nothing). registerAllClasses() is
// for the plugin and the programs, which call it once everything is loaded.
