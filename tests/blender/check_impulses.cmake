# The ctest blender_impulses: Blender imports `spotshell impulses` with every attribute.
#
#   cmake -DBLENDER=... -DSPOTSHELL=... -DSOURCE=... -DOUT=file.ply -P check_impulses.cmake
#
# Writes the impulses of the fur preset on the bunny, then runs tests/blender/check_impulses.py in
# Blender (background mode), which imports them with scripts/blender/spotshell_impulses.py and
# compares every point's attributes with the PLY. Blender is a dependency (scripts/install-deps.sh):
# a missing one fails the test.
foreach(v SPOTSHELL SOURCE OUT)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "check_impulses.cmake: -D${v}=... missing")
  endif()
endforeach()
if(NOT BLENDER OR NOT EXISTS "${BLENDER}")
  message(FATAL_ERROR "Blender not found: run scripts/install-deps.sh (Debian's blender)")
endif()
execute_process(COMMAND "${SPOTSHELL}" impulses --mesh "${SOURCE}/presets/meshes/bunny.ply"
                        --preset "${SOURCE}/presets/fur.json" --seed 5 --out "${OUT}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "spotshell impulses failed (exit ${rc}): ${err}")
endif()
execute_process(COMMAND "${BLENDER}" -b --factory-startup --python-exit-code 1
                        --python "${SOURCE}/tests/blender/check_impulses.py" -- "${SOURCE}" "${OUT}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCH "check_impulses: [^\n]*" summary "${out}")
if(NOT rc EQUAL 0 OR NOT summary MATCHES "every attribute equal")
  message(FATAL_ERROR "Blender's import failed its checks (exit ${rc}):\n${out}\n${err}")
endif()
message(STATUS "${summary}")
