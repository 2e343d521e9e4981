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
#include <BRepCheck_Analyzer.hxx>
#include <BRep_Tool.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <gp_Pnt.hxx>

#include <cstdio>
#include <cstring>

static int run(const char *path, const char *out)
{
    // OCCT reports progress on std::cout; stdout must carry only the points.
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
    STEPControl_Reader rd;
    if (rd.ReadFile(path) != IFSelect_RetDone) {
        std::fprintf(stderr, "occt_step: %s: STEPControl_Reader cannot read it\n", path);
        return 2;
    }
    int roots = rd.NbRootsForTransfer();
    int done = rd.TransferRoots();
    TopoDS_Shape shape = rd.OneShape();
    int nf = 0, ne = 0;
    for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next())
        nf++;
    TopExp_Explorer ex(shape, TopAbs_FACE);
    std::fprintf(stderr, "occt_step: %d root(s), %d transferred, %d face(s)\n", roots, done, nf);
    if (!ex.More())
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
    TopoDS_Face face = TopoDS::Face(ex.Current());
    for (TopExp_Explorer e(face, TopAbs_EDGE); e.More(); e.Next())
        ne++;
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
    Handle(Geom_Surface) basis = surf;
    Handle(Geom_RectangularTrimmedSurface) tr =
        Handle(Geom_RectangularTrimmedSurface)::DownCast(surf);
    if (!tr.IsNull())
        basis = tr->BasisSurface();
    Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(basis);
    if (bs.IsNull())
        std::fprintf(stderr, "occt_step: surface type %s, not Geom_BSplineSurface\n",
                     basis->DynamicType()->Name());
    else
        std::fprintf(stderr,
                     "occt_step: %d edge(s); degrees %d %d, poles %d x %d, rational %d %d, "
                     "location %s\n",
                     ne, bs->UDegree(), bs->VDegree(), bs->NbUPoles(), bs->NbVPoles(),
                     (int)bs->IsURational(), (int)bs->IsVRational(),
                     loc.IsIdentity() ? "identity" : "non-identity");
    char line[512];
    while (std::fgets(line, sizeof line, stdin)) {
        double u, v;
        if (std::sscanf(line, "%lf %lf", &u, &v) != 2)
            continue;
        gp_Pnt p;
        surf->D0(u, v, p);
        if (!loc.IsIdentity())
            p.Transform(loc.Transformation());
        std::printf("%.17g %.17g %.17g\n", p.X(), p.Y(), p.Z());
    }
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
