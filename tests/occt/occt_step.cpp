/* SPDX-License-Identifier: MIT */
// occt_step.cpp: read a STEP file with OpenCASCADE's STEPControl_Reader, as
// an independent check of cf_step: the file must transfer to exactly one
// face (the count, the face's edges and BRepCheck's verdict go to stderr); for each "u v" line on
// stdin, the face's surface (with its location) at (u, v) is printed as
// "x y z" with %.17g. Exit 2 when OCCT cannot read it or finds no face,
// 3 when it finds more than one.
// With --write OUT.stp, the shape read is also written by OCCT's own
// STEPControl_Writer (as a shell-based surface model, mm), so that our
// reader can be checked on a file we did not write.
// Usage: occt_step [--write OUT.stp] FILE.stp < uv.txt
#include "occt_shape.hxx"

#include <BRepCheck_Analyzer.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>

static int run(const char *path, const char *out)
{
    occt_quiet();
    TopoDS_Shape shape;
    int roots = 0, done = 0;
    if (!occt_read_step(path, shape, &roots, &done)) {
        std::fprintf(stderr, "occt_step: %s: STEPControl_Reader cannot read it\n", path);
        return 2;
    }
    int nf = occt_count(shape, TopAbs_FACE);
    std::fprintf(stderr, "occt_step: %d root(s), %d transferred, %d face(s)\n", roots, done, nf);
    TopoDS_Face face;
    if (!occt_first_face(shape, face))
        return 2;
    if (out) {
        STEPControl_Writer wr;
        Interface_Static::SetCVal("write.step.unit", "MM");
        if (wr.Transfer(shape, STEPControl_ShellBasedSurfaceModel) != IFSelect_RetDone ||
            wr.Write(out) != IFSelect_RetDone) {
            std::fprintf(stderr, "occt_step: STEPControl_Writer cannot write %s\n", out);
            return 2;
        }
    }
    int ne = occt_count(face, TopAbs_EDGE);
    // The topology as OCCT's checker sees it: edges on the surface, a
    // closed wire, vertices within tolerance.
    BRepCheck_Analyzer chk(shape);
    std::fprintf(stderr, "occt_step: BRepCheck valid %d\n", (int)chk.IsValid());
    TopLoc_Location loc;
    Handle(Geom_Surface) surf = BRep_Tool::Surface(face, loc);
    if (surf.IsNull()) {
        std::fprintf(stderr, "occt_step: %s: face without a surface\n", path);
        return 2;
    }
    char d[256];
    occt_describe(surf, loc, d, sizeof d);
    if (std::strncmp(d, "degrees", 7))
        std::fprintf(stderr, "occt_step: %s\n", d);
    else
        std::fprintf(stderr, "occt_step: %d edge(s); %s\n", ne, d);
    occt_eval_stdin(surf, loc, "");
    return nf == 1 ? 0 : 3;
}

int main(int argc, char **argv)
{
    const char *out = nullptr, *path = nullptr;
    for (int i = 1; i < argc; i++) {
        if (!std::strcmp(argv[i], "--write") && i + 1 < argc)
            out = argv[++i];
        else
            path = argv[i];
    }
    if (!path) {
        std::fprintf(stderr, "usage: occt_step [--write OUT.stp] FILE.stp < uv.txt\n");
        return 1;
    }
    try {
        return run(path, out);
    } catch (Standard_Failure &e) {
        std::fprintf(stderr, "occt_step: OpenCASCADE exception: %s\n", e.GetMessageString());
        return 2;
    }
}
