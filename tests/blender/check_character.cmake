# The ctest blender_character: the example character (examples/character/character.glb) is what
# scripts/make_character.py makes in Blender today.
#
#   cmake -DBLENDER=... -DSPOTSHELL=... -DSOURCE=... -DOUT=file.glb -P check_character.cmake
#
# Runs the script in Blender (glTF Binary, animation on), then `spotshell info` on the new file
# and on the shipped one: the same vertices, welded vertices and shared positions, triangles,
# meshes, nodes, materials (the embedded texture), parts, clip and frames (Blender's 1 to 25).
# The bytes may differ between Blender builds (the exporter's version string); what spotshell
# reads of them must not.
foreach(v BLENDER SPOTSHELL SOURCE OUT)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "check_character.cmake: -D${v}=... missing")
  endif()
endforeach()
file(REMOVE "${OUT}")
execute_process(COMMAND "${BLENDER}" -b --factory-startup --python-exit-code 1
                        --python "${SOURCE}/scripts/make_character.py" -- "${OUT}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS "${OUT}")
  message(FATAL_ERROR "Blender's export failed (exit ${rc}):\n${out}\n${err}")
endif()
file(SIZE "${OUT}" bytes)
if(bytes GREATER 65536)
  message(FATAL_ERROR "${OUT} is ${bytes} bytes: the test asset should stay a few tens of KB")
endif()
function(info var file)
  execute_process(COMMAND "${SPOTSHELL}" info --mesh "${file}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE text ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "spotshell info --mesh ${file} failed (exit ${rc}): ${err}")
  endif()
  # The first line names the file; the rest must agree.
  string(REGEX REPLACE "^mesh [^\n]*\n" "" text "${text}")
  set(${var} "${text}" PARENT_SCOPE)
endfunction()
info(made "${OUT}")
info(shipped "${SOURCE}/examples/character/character.glb")
message(STATUS "spotshell info of the new export:\n${made}")
if(NOT made STREQUAL shipped)
  message(FATAL_ERROR "the new export differs from examples/character/character.glb:\n"
                      "--- made:\n${made}\n--- shipped:\n${shipped}")
endif()
foreach(expect "frames     1-25 at 24 fps" "texture 'fur_colour' \\(embedded" "meshes     2: 0 'Stand', 1 'Body'")
  if(NOT made MATCHES "${expect}")
    message(FATAL_ERROR "no '${expect}' in:\n${made}")
  endif()
endforeach()
message(STATUS "blender_character: passed")
