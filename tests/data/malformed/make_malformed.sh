#!/usr/bin/env bash
# Writes the malformed-PLY set next to this script (committed; rerun after changes).
# Each file is one row of reference/reliability.md section 4.1 or one header rule; the
# expected error of each is listed in tests/unit/test_ply_malformed.c, which also builds
# the cases that are too large to commit (10 MB header line, every truncation offset).
# Needs only bash and coreutils.
set -euo pipefail
cd "$(dirname "$0")"
rm -f ./*.ply

hdr_ascii='ply\nformat ascii 1.0\n'
hdr_le='ply\nformat binary_little_endian 1.0\n'
xyz='property float x\nproperty float y\nproperty float z\n'
# 3 vertices (0,0,0) (1,0,0) (0,1,0): 36 bytes of little-endian floats
tri_le='\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x80\x3f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x80\x3f\x00\x00\x00\x00'

put() { printf "$2" > "$1"; }

put empty.ply ''
put garbage_header.ply '\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x01\x00'
put no_end_header.ply "${hdr_ascii}element vertex 1\n${xyz}"
put no_end_header_body.ply "${hdr_ascii}element vertex 1\n${xyz}1 2 3\n"
put cr_only_lines.ply 'ply\rformat ascii 1.0\relement vertex 1\rproperty float x\rend_header\r1\r'
put format_missing.ply "ply\nelement vertex 1\n${xyz}end_header\n1 2 3\n"
put unknown_format.ply "ply\nformat binary_middle_endian 1.0\nelement vertex 1\n${xyz}end_header\n"
put unknown_version.ply "ply\nformat ascii 2.0\nelement vertex 1\n${xyz}end_header\n1 2 3\n"
put unknown_type.ply "${hdr_ascii}element vertex 1\nproperty float128 x\nend_header\n1\n"
put negative_count.ply "${hdr_ascii}element vertex -5\n${xyz}end_header\n"
put property_before_element.ply "${hdr_ascii}property float x\nelement vertex 1\n${xyz}end_header\n1 2 3\n"
put duplicate_vertex_element.ply "${hdr_ascii}element vertex 1\n${xyz}element vertex 1\n${xyz}end_header\n1 2 3\n1 2 3\n"
put duplicate_property.ply "${hdr_ascii}element vertex 1\n${xyz}property double x\nend_header\n1 2 3 4\n"
put missing_xyz.ply "${hdr_ascii}element vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n"
put list_in_vertex.ply "${hdr_ascii}element vertex 1\nproperty list uchar float x\nproperty float y\nproperty float z\nend_header\n1 1 2 3\n"
put scalar_indices.ply "${hdr_ascii}element vertex 1\n${xyz}element face 1\nproperty int vertex_indices\nend_header\n1 2 3\n0\n"
put float_count_type.ply "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list float int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
put float_index_type.ply "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
put face_without_indices.ply "${hdr_ascii}element vertex 1\n${xyz}element face 1\nproperty uchar flags\nend_header\n1 2 3\n0\n"
put texture_name_too_long.ply "${hdr_ascii}comment TextureFile $(printf 'a%.0s' {1..300}).png\nelement vertex 1\n${xyz}end_header\n1 2 3\n"
{ printf "$hdr_ascii"; for i in $(seq 65); do printf 'element e%d 0\n' "$i"; done; printf 'end_header\n'; } > too_many_elements.ply

# Counts the file cannot hold (near 2^32 and 2^64), in files of about 100 bytes.
put vertex_2e32.ply "${hdr_ascii}element vertex 4294967295\n${xyz}end_header\n1 2 3\n"
put vertex_2e32_binary.ply "${hdr_le}element vertex 4294967295\n${xyz}end_header\n${tri_le}"
put vertex_2e64_minus_1.ply "${hdr_le}element vertex 18446744073709551615\n${xyz}end_header\n${tri_le}"
put count_2e64.ply "${hdr_ascii}element vertex 18446744073709551616\n${xyz}end_header\n1 2 3\n"
put face_2e32.ply "${hdr_le}element vertex 3\n${xyz}element face 4294967296\nproperty list uchar int vertex_indices\nend_header\n${tri_le}\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00"
{ printf "${hdr_le}element vertex 3\n${xyz}element face 1000000000\nproperty list uchar int vertex_indices\nend_header\n${tri_le}"
  for i in $(seq 10); do printf '\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00'; done; } > faces_1e9_with_10.ply

# List counts: huge, negative, beyond the corner limit.
put list_count_huge.ply "${hdr_le}element vertex 3\n${xyz}element face 1\nproperty list uint int vertex_indices\nend_header\n${tri_le}\xff\xff\xff\xff\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00"
put list_count_huge_ascii.ply "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list uint int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n4294967295 0 1 2\n"
put list_count_negative.ply "${hdr_le}element vertex 3\n${xyz}element face 1\nproperty list int int vertex_indices\nend_header\n${tri_le}\xff\xff\xff\xff\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00"
put list_count_negative_ascii.ply "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list char int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n"
{ printf "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list ushort int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n2000"
  for i in $(seq 2000); do printf ' %d' $((i % 3)); done; printf '\n'; } > list_too_many_corners.ply
put int_out_of_range.ply "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n"
put texcoord_mismatch.ply "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 5 0 0 1 0 1\n"

# Indices: out of range, negative, and data written little endian but declared big.
put index_out_of_range.ply "${hdr_ascii}element vertex 3\n${xyz}element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 5\n"
put index_negative.ply "${hdr_le}element vertex 3\n${xyz}element face 1\nproperty list uchar int vertex_indices\nend_header\n${tri_le}\x03\x00\x00\x00\x00\xff\xff\xff\xff\x02\x00\x00\x00"
put index_negative_ascii.ply "${hdr_ascii}element vertex 3\n${xyz}element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"
put range_grid_bad_index.ply "${hdr_ascii}obj_info num_cols 2\nobj_info num_rows 1\nelement vertex 1\n${xyz}element range_grid 2\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n1 0\n1 99\n"
put wrong_endianness.ply "ply\nformat binary_big_endian 1.0\nelement vertex 3\n${xyz}element face 1\nproperty list uchar int vertex_indices\nend_header\n${tri_le}\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00"

# Non-finite coordinates are read (the range stage counts and drops them).
put all_nan.ply "${hdr_le}element vertex 3\n${xyz}element face 1\nproperty list uchar int vertex_indices\nend_header\n$(printf '\\x00\\x00\\xc0\\x7f%.0s' {1..9})\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00"
put nan_inf_ascii.ply "${hdr_ascii}element vertex 2\n${xyz}end_header\nnan inf -inf\nNaN -nan 1e999\n"

# Bodies shorter or longer than the header says, and bad tokens.
put truncated_binary_header.ply "${hdr_le}element vertex 3\n${xyz}end_header\n\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x80"
put truncated_binary.ply "${hdr_le}element vertex 3\n${xyz}element face 2\nproperty list uchar int vertex_indices\nend_header\n${tri_le}\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00\x03\x00\x00\x00\x00\x01\x00"
put truncated_ascii.ply "${hdr_ascii}element vertex 3\n${xyz}element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0"
put trailing_bytes_binary.ply "${hdr_le}element vertex 3\n${xyz}end_header\n${tri_le}\x00\x01"
put trailing_garbage_ascii.ply "${hdr_ascii}element vertex 1\n${xyz}end_header\n1 2 3\nhello\n"
put bad_number.ply "${hdr_ascii}element vertex 1\n${xyz}end_header\n1.0 abc 3.0\n"
