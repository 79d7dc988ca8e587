# Writes the text file INPUT as a NUL-terminated C string surge_default_case_text into OUTPUT.
file(READ "${INPUT}" hex HEX)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
file(WRITE "${OUTPUT}" "/* generated from ${INPUT}; do not edit */\nconst char surge_default_case_text[] = {${bytes}0x00};\n")
