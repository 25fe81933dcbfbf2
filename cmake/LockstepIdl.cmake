# IDL to code, one call per generator (see idl/CMakeLists.txt).

# lockstep_fastdds_idl(target INCLUDE_DIR dir OUTPUT_SUBDIR sub FILES a.idl ...)
# Generates C++ types and PubSubTypes with fastddsgen into <build>/gen/<sub>/ and
# builds them into a static library. Users include "<sub>/<name>PubSubTypes.h".
function(lockstep_fastdds_idl target)
  cmake_parse_arguments(G "" "INCLUDE_DIR;OUTPUT_SUBDIR" "FILES" ${ARGN})
  find_program(FASTDDSGEN fastddsgen REQUIRED)
  set(gen_root ${CMAKE_CURRENT_BINARY_DIR}/gen_fastdds)
  set(out ${gen_root}/${G_OUTPUT_SUBDIR})
  file(MAKE_DIRECTORY ${out})
  # A temporary folder of this build: fastddsgen's default (/tmp, fixed file names) is
  # shared by every build on the machine, and parallel builds overwrite each other's files.
  set(tmp ${CMAKE_CURRENT_BINARY_DIR}/fastddsgen_tmp)
  file(MAKE_DIRECTORY ${tmp})
  set(srcs)
  foreach(idl ${G_FILES})
    get_filename_component(name ${idl} NAME_WE)
    set(generated ${out}/${name}.h ${out}/${name}.cxx ${out}/${name}PubSubTypes.h ${out}/${name}PubSubTypes.cxx)
    # fastddsgen preprocesses into <tmp>/<name>.idl.cc; the default /tmp is shared by
    # every checkout on the machine, so concurrent builds read each other's files.
    set(tmp ${gen_root}/tmp/${name})
    file(MAKE_DIRECTORY ${tmp})
    add_custom_command(
      OUTPUT ${generated}
      COMMAND ${FASTDDSGEN} -replace -t ${tmp} -I ${G_INCLUDE_DIR} -d ${out} ${idl}
      DEPENDS ${G_FILES}
      COMMENT "fastddsgen ${name}.idl"
      VERBATIM)
    list(APPEND srcs ${out}/${name}.cxx ${out}/${name}PubSubTypes.cxx)
  endforeach()
  add_library(${target} STATIC ${srcs})
  target_include_directories(${target} SYSTEM PUBLIC ${gen_root})
  target_link_libraries(${target} PUBLIC fastrtps fastcdr)
  # Generated code: not ours to keep warning-clean.
  target_compile_options(${target} PRIVATE -w)
endfunction()

# lockstep_cyclone_idl(target INCLUDE_DIR dir FILES a.idl ...)
# C types for Cyclone DDS from the same files; users include "lockstep/<name>.h".
function(lockstep_cyclone_idl target)
  cmake_parse_arguments(G "" "INCLUDE_DIR" "FILES" ${ARGN})
  idlc_generate(TARGET ${target}_gen FILES ${G_FILES} INCLUDES ${G_INCLUDE_DIR} BASE_DIR ${G_INCLUDE_DIR})
  add_library(${target} INTERFACE)
  target_link_libraries(${target} INTERFACE ${target}_gen CycloneDDS::ddsc)
endfunction()
