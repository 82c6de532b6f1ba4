# vkray_embed_shaders(TARGET <name> SHADERS <file.comp>[:<DEFINE>[+<DEFINE>...][:<TARGET_ENV>]]...)
# Compiles GLSL compute shaders to SPIR-V with glslangValidator at build time and embeds each as a
# uint32_t array in a generated header, so the binary needs no shader files at run time:
# raycast.comp -> raycast_comp in raycast.comp.spv.h; raycast.comp:VKRAY_FLOAT64 compiles the same
# file with VKRAY_FLOAT64 defined -> raycast_comp_VKRAY_FLOAT64 in raycast.comp.VKRAY_FLOAT64.spv.h.
# TARGET_ENV is glslang's --target-env (default vulkan1.1: SPIR-V 1.3); ray queries need vulkan1.2.
# glslang writes a depfile, so editing any #included file recompiles the shader. <name> is an
# interface library that carries the include path and the build order.
function(vkray_embed_shaders)
  cmake_parse_arguments(ARG "" "TARGET" "SHADERS" ${ARGN})
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/generated)
  set(headers)
  foreach(entry IN LISTS ARG_SHADERS)
    string(REPLACE ":" ";" parts ${entry})
    list(GET parts 0 shader)
    set(name ${shader})
    set(define_flags)
    list(LENGTH parts part_count)
    set(target_env vulkan1.1)
    if(part_count GREATER 2)
      list(GET parts 2 target_env)
    endif()
    if(part_count GREATER 1)  # shader.comp:A+B compiles with A and B defined, as shader.comp.A.B
      list(GET parts 1 defines)
      string(REPLACE "+" ";" defines ${defines})
      foreach(define IN LISTS defines)
        set(name ${name}.${define})
        list(APPEND define_flags -D${define})
      endforeach()
    endif()
    string(MAKE_C_IDENTIFIER ${name} array_name)
    set(source ${CMAKE_CURRENT_SOURCE_DIR}/${shader})
    set(header ${out_dir}/${name}.spv.h)
    add_custom_command(
      OUTPUT ${header}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
      COMMAND ${GLSLANG_VALIDATOR} --quiet --target-env ${target_env} ${define_flags} --vn ${array_name}
              --depfile ${header}.d -o ${header} ${source}
      DEPENDS ${source}
      DEPFILE ${header}.d
      COMMENT "Compiling ${name} to SPIR-V"
      VERBATIM)
    list(APPEND headers ${header})
  endforeach()
  add_custom_target(${ARG_TARGET}_spirv DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  target_include_directories(${ARG_TARGET} INTERFACE ${out_dir})
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_spirv)
endfunction()
