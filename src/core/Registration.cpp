/* ShadyLoc — one place that registers every class (like MRPT's
 * registerAllClasses.cpp per library). Add new classes here. */
#include <shadyloc/core/Registration.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <mrpt/core/initializer.h>
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

MRPT_INITIALIZER(shadyloc_register_all_classes) { shadyloc::registerAllClasses(); }
