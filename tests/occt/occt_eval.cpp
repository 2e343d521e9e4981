/* SPDX-License-Identifier: MIT */
// occt_eval.cpp: evaluate an IGES surface with OpenCASCADE, as an independent
// check of cf_iges and nf_surf_eval. Reads the file with IGESControl_Reader,
// takes the first face's underlying surface (with the face's location), then
// for each "u v" line on stdin prints "x y z" with %.17g. Degrees, pole counts
// and rationality go to stderr; --info adds the surface and face UV bounds.
// Usage: occt_eval [--info] FILE.igs < uv.txt
#include "occt_shape.hxx"

#include <BRepTools.hxx>
#include <Standard_Failure.hxx>

static int run(const char *path, bool info)
{
    occt_quiet();
    TopoDS_Shape shape;
    if (!occt_read_iges(path, shape)) {
        std::fprintf(stderr, "occt_eval: %s: IGESControl_Reader cannot read it\n", path);
        return 2;
    }
    TopoDS_Face face;
    if (!occt_first_face(shape, face)) {
        std::fprintf(stderr, "occt_eval: %s: no face after transfer\n", path);
        return 2;
    }
    TopLoc_Location loc;
    Handle(Geom_Surface) surf = BRep_Tool::Surface(face, loc);
    if (surf.IsNull()) {
        std::fprintf(stderr, "occt_eval: %s: face without a surface\n", path);
        return 2;
    }
    char d[256];
    occt_describe(surf, loc, d, sizeof d);
    std::fprintf(stderr, "occt_eval: %s\n", d);
    if (info) {
        double u0, u1, v0, v1;
        surf->Bounds(u0, u1, v0, v1);
        std::fprintf(stderr, "occt_eval: surface bounds u [%.17g, %.17g] v [%.17g, %.17g]\n", u0,
                     u1, v0, v1);
        BRepTools::UVBounds(face, u0, u1, v0, v1);
        std::fprintf(stderr, "occt_eval: face bounds u [%.17g, %.17g] v [%.17g, %.17g]\n", u0, u1,
                     v0, v1);
        std::fprintf(stderr, "occt_eval: %d face(s) in the file\n",
                     occt_count(shape, TopAbs_FACE));
    }
    occt_eval_stdin(surf, loc, "");
    return 0;
}

int main(int argc, char **argv)
{
    bool info = false;
    const char *path = nullptr;
    for (int i = 1; i < argc; i++) {
        if (!std::strcmp(argv[i], "--info"))
            info = true;
        else
            path = argv[i];
    }
    if (!path) {
        std::fprintf(stderr, "usage: occt_eval [--info] FILE.igs < uv.txt\n");
        return 1;
    }
    try {
        return run(path, info);
    } catch (Standard_Failure &e) {
        std::fprintf(stderr, "occt_eval: OpenCASCADE exception: %s\n", e.GetMessageString());
        return 2;
    }
}
