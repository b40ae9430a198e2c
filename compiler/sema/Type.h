// Types of the math language: scalars, integers, vectors and matrices with sizes, booleans (conditions);
// and, in the IR only, tuples (a loop's results) and fixed-size arrays of scalars, vectors or matrices
// (per-instance data of the scene, sequences).
#pragma once

#include <string>

namespace iqc {

struct Type {
    enum Kind : unsigned char { Invalid, Scalar, Integer, Vector, Matrix, Bool, Tuple, Array } kind = Invalid;
    int rows = 1, cols = 1;  // Vector: rows = size; Matrix: rows × cols; Array: its element's
    Kind elem = Invalid;     // Array: the element's kind (Scalar, Integer, Vector or Matrix)
    int count = 0;           // Array: the number of elements

    static Type invalid() { return {}; }
    static Type scalar() { return {Scalar, 1, 1}; }
    static Type integer() { return {Integer, 1, 1}; }
    static Type boolean() { return {Bool, 1, 1}; }
    static Type vector(int n) { return n == 1 ? scalar() : Type{Vector, n, 1}; }
    static Type matrix(int r, int c) { return {Matrix, r, c}; }
    static Type tuple(int n) { return {Tuple, n, 1}; }  // a loop's results (IR only)
    // n elements of type e (IR only; e is a scalar, vector or matrix).
    static Type array(const Type& e, int n) { return {Array, e.rows, e.cols, e.kind, n}; }
    // An array's element type.
    Type element() const { return kind == Array ? Type{elem, rows, cols} : Type{}; }

    bool valid() const { return kind != Invalid; }
    bool is_scalar() const { return kind == Scalar || kind == Integer; }
    bool is_vector() const { return kind == Vector; }
    bool is_matrix() const { return kind == Matrix; }
    bool is_numeric() const { return kind == Scalar || kind == Integer || kind == Vector || kind == Matrix; }
    bool is_array() const { return kind == Array; }
    // Scalar components (an array: all of its elements' components).
    int components() const {
        int n = (kind == Vector || elem == Vector) ? rows : (kind == Matrix || elem == Matrix) ? rows * cols : 1;
        return kind == Array ? n * count : n;
    }
    bool operator==(const Type& o) const {
        return kind == o.kind && rows == o.rows && cols == o.cols && elem == o.elem && count == o.count;
    }
    bool operator!=(const Type& o) const { return !(*this == o); }
    bool operator<(const Type& o) const {
        if (kind != o.kind) return kind < o.kind;
        if (rows != o.rows) return rows < o.rows;
        if (cols != o.cols) return cols < o.cols;
        return elem != o.elem ? elem < o.elem : count < o.count;
    }
    // Math spelling: ℝ, ℤ, ℝ³, ℝ^(3×4), bool.
    std::string str() const;
};

}  // namespace iqc
