/* ShadyLoc MRPT plugin: a shared module MRPT tools load with
 *   rawlog-edit -p ./libshadyloc_mrpt_plugin.so ...
 *   RawLogViewer -l ./libshadyloc_mrpt_plugin.so
 * Loading it registers every ShadyLoc class, so rawlogs and maps that hold
 * them can be read: the one list (shadyloc::registerAllClasses, at the top of
 * libshadyloc_localisation) runs when the library loads and again here, once
 * the library is fully initialised. */
#include <shadyloc/Registration.h>

#include <mrpt/core/initializer.h>

MRPT_INITIALIZER(shadyloc_plugin_init) { shadyloc::registerAllClasses(); }
