/* ShadyLoc — registration of our classes with MRPT's RTTI system. */
#pragma once

namespace shadyloc
{
/** Registers every RTTI/serialisable class of ShadyLoc (idempotent). Runs by
 * itself when libshadyloc loads; the plugin and apps call it explicitly too. */
void registerAllClasses();
}  // namespace shadyloc
