# iqc_add_shader(<name> SCENE <file> TARGET <target> OUTPUT <file> [META <json>] [ARGS <arg>...])
#
# Compiles an iqc scene (.iq), document (.md) or shape module (.iql) at build time into OUTPUT, with iqc's
# --target TARGET (shadertoy, webgl2, glsl330, html: `iqc --help`), and the JSON description of its
# parameters into META when given. A custom target <name> (built by default) owns the outputs: targets that
# use them depend on it (add_dependencies).
#
# iqc writes a depfile naming every file the compile read (the scene, its `include`s and the module files it
# looked up, wherever they are), so Ninja and Makefiles rebuild exactly when one of them, or iqc itself,
# changes; iqc leaves an output whose bytes did not change untouched. Relative SCENE paths are relative to
# the current source directory, relative OUTPUT and META paths to the current binary directory; their folders
# are created as needed. ARGS are passed to iqc as they are (e.g. --strict-ranges).
function(iqc_add_shader name)
  cmake_parse_arguments(PARSE_ARGV 1 IQC "" "SCENE;TARGET;OUTPUT;META" "ARGS")
  if(IQC_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "iqc_add_shader(${name}): unknown arguments: ${IQC_UNPARSED_ARGUMENTS}")
  endif()
  foreach(required SCENE OUTPUT)
    if(NOT IQC_${required})
      message(FATAL_ERROR "iqc_add_shader(${name}): ${required} <file> is required")
    endif()
  endforeach()
  if(NOT IQC_TARGET)
    set(IQC_TARGET shadertoy)
  endif()
  if(NOT TARGET iqc::iqc)
    message(FATAL_ERROR "iqc_add_shader(${name}): the imported executable iqc::iqc is missing (find_package(iqc) first)")
  endif()
  cmake_path(ABSOLUTE_PATH IQC_SCENE BASE_DIRECTORY "${CMAKE_CURRENT_SOURCE_DIR}" NORMALIZE)
  cmake_path(ABSOLUTE_PATH IQC_OUTPUT BASE_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}" NORMALIZE)
  set(meta_args)
  set(byproducts)
  if(IQC_META)
    cmake_path(ABSOLUTE_PATH IQC_META BASE_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}" NORMALIZE)
    # A byproduct, not a second OUTPUT: Makefile generators touch every OUTPUT but the first after the
    # command, which would defeat iqc's leaving unchanged files alone. Depend on the target <name> for it.
    set(byproducts BYPRODUCTS "${IQC_META}")
    set(meta_args --meta "${IQC_META}")
  endif()
  set(dirs)
  foreach(out IN ITEMS "${IQC_OUTPUT}" ${IQC_META})
    cmake_path(GET out PARENT_PATH dir)
    list(APPEND dirs "${dir}")
  endforeach()
  list(REMOVE_DUPLICATES dirs)
  set(depfile "${CMAKE_CURRENT_BINARY_DIR}/CMakeFiles/${name}.iqc.d")
  add_custom_command(
    OUTPUT "${IQC_OUTPUT}"
    ${byproducts}
    COMMAND "${CMAKE_COMMAND}" -E make_directory ${dirs}
    COMMAND iqc::iqc "${IQC_SCENE}" --target "${IQC_TARGET}" -o "${IQC_OUTPUT}" ${meta_args}
            --depfile "${depfile}" --quiet ${IQC_ARGS}
    DEPENDS "${IQC_SCENE}" iqc::iqc
    DEPFILE "${depfile}"
    COMMENT "iqc: ${name} (${IQC_TARGET})"
    VERBATIM)
  add_custom_target(${name} ALL DEPENDS "${IQC_OUTPUT}")
endfunction()
