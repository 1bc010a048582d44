// magdem's bridge to LIGGGHTS 3.8's fix external: its library has no C function to set the
// callback, so this sets it on the fix with the given id. Built by build.rs (feature
// liggghts-shim) into a shared object that magdem loads at run time.
#include "lammps.h"
#include "modify.h"
#include "fix_external.h"

using namespace LAMMPS_NS;

extern "C" int magdem_liggghts_set_callback(void *handle, const char *fix_id,
                                            FixExternal::FnPtr callback, void *data) {
  LAMMPS *lmp = static_cast<LAMMPS *>(handle);
  int index = lmp->modify->find_fix(fix_id);
  if (index < 0) return 1;
  FixExternal *fix = dynamic_cast<FixExternal *>(lmp->modify->fix[index]);
  if (fix == nullptr) return 2;
  fix->set_callback(callback, data);
  return 0;
}
