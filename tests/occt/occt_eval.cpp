/* SPDX-License-Identifier: MIT */
// occt_eval.cpp: evaluate an IGES surface with OpenCASCADE, as an independent
// check of cf_iges and nf_surf_eval. Reads the file with IGESControl_Reader,
// takes the first face's underlying surface (with the face's location), then
// for each "u v" line on stdin prints "x y z" with %.17g. Degrees, pole counts
// and rationality go to stderr; --info adds the surface and face UV bounds.
// Usage: occt_eval [--info] FILE.igs < uv.txt
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <gp_Pnt.hxx>

#include <cstdio>
#include <cstring>

static int run(const char *path, bool info)
{
    // OCCT reports progress on std::cout; stdout must carry only the points.
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
    IGESControl_Reader rd;
    // Keep the B-spline as written: no splitting of C0 patches into faces.
    Interface_Static::SetIVal("read.iges.bspline.continuity", 0);
    if (rd.ReadFile(path) != IFSelect_RetDone) {
        std::fprintf(stderr, "occt_eval: %s: IGESControl_Reader cannot read it\n", path);
        return 2;
    }
    rd.TransferRoots();
    TopoDS_Shape shape = rd.OneShape();
    TopExp_Explorer ex(shape, TopAbs_FACE);
    if (!ex.More()) {
        std::fprintf(stderr, "occt_eval: %s: no face after transfer\n", path);
        return 2;
    }
    TopoDS_Face face = TopoDS::Face(ex.Current());
    TopLoc_Location loc;
    Handle(Geom_Surface) surf = BRep_Tool::Surface(face, loc);
    if (surf.IsNull()) {
        std::fprintf(stderr, "occt_eval: %s: face without a surface\n", path);
        return 2;
    }
    Handle(Geom_Surface) basis = surf;
    Handle(Geom_RectangularTrimmedSurface) tr =
        Handle(Geom_RectangularTrimmedSurface)::DownCast(surf);
    if (!tr.IsNull())
        basis = tr->BasisSurface();
    Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(basis);
    if (bs.IsNull())
        std::fprintf(stderr, "occt_eval: surface type %s, not Geom_BSplineSurface\n",
                     basis->DynamicType()->Name());
    else
        std::fprintf(
            stderr, "occt_eval: degrees %d %d, poles %d x %d, rational %d %d, location %s\n",
            bs->UDegree(), bs->VDegree(), bs->NbUPoles(), bs->NbVPoles(), (int)bs->IsURational(),
            (int)bs->IsVRational(), loc.IsIdentity() ? "identity" : "non-identity");
    if (info) {
        double u0, u1, v0, v1;
        surf->Bounds(u0, u1, v0, v1);
        std::fprintf(stderr, "occt_eval: surface bounds u [%.17g, %.17g] v [%.17g, %.17g]\n", u0,
                     u1, v0, v1);
        BRepTools::UVBounds(face, u0, u1, v0, v1);
        std::fprintf(stderr, "occt_eval: face bounds u [%.17g, %.17g] v [%.17g, %.17g]\n", u0, u1,
                     v0, v1);
        int nf = 0;
        for (TopExp_Explorer e2(shape, TopAbs_FACE); e2.More(); e2.Next())
            nf++;
        std::fprintf(stderr, "occt_eval: %d face(s) in the file\n", nf);
    }
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
