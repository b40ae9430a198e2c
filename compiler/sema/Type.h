// Types of the math language: scalars, integers, vectors and matrices with sizes, booleans (conditions).
#pragma once

#include <string>

namespace iqc {

struct Type {
    enum Kind : unsigned char { Invalid, Scalar, Integer, Vector, Matrix, Bool, Tuple } kind = Invalid;
    int rows = 1, cols = 1;  // Vector: rows = size; Matrix: rows × cols

    static Type invalid() { return {}; }
    static Type scalar() { return {Scalar, 1, 1}; }
    static Type integer() { return {Integer, 1, 1}; }
    static Type boolean() { return {Bool, 1, 1}; }
    static Type vector(int n) { return n == 1 ? scalar() : Type{Vector, n, 1}; }
    static Type matrix(int r, int c) { return {Matrix, r, c}; }
    static Type tuple(int n) { return {Tuple, n, 1}; }  // a loop's results (IR only)

    bool valid() const { return kind != Invalid; }
    bool is_scalar() const { return kind == Scalar || kind == Integer; }
    bool is_vector() const { return kind == Vector; }
    bool is_matrix() const { return kind == Matrix; }
    bool is_numeric() const { return kind == Scalar || kind == Integer || kind == Vector || kind == Matrix; }
    int components() const { return kind == Vector ? rows : kind == Matrix ? rows * cols : 1; }
    bool operator==(const Type& o) const { return kind == o.kind && rows == o.rows && cols == o.cols; }
    bool operator!=(const Type& o) const { return !(*this == o); }
    bool operator<(const Type& o) const {
        return kind != o.kind ? kind < o.kind : rows != o.rows ? rows < o.rows : cols < o.cols;
    }
    // Math spelling: ℝ, ℤ, ℝ³, ℝ^(3×4), bool.
    std::string str() const;
};

}  // namespace iqc
