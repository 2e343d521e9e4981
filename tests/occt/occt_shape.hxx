/* SPDX-License-Identifier: MIT */
// occt_shape.hxx: what the OpenCASCADE test programs (occt_eval,
// occt_step, occt_trim) share: OCCT's console printer silenced (stdout
// carries only their output), an IGES or STEP file read into one shape
// (IGES B-splines kept as written, not split at C0 knots), its faces
// counted, a face's surface with its location described, and the surface
// evaluated at each "u v" line of stdin.
#ifndef OCCT_SHAPE_HXX
#define OCCT_SHAPE_HXX

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
#include <STEPControl_Reader.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <gp_Pnt.hxx>

#include <cctype>
#include <cstdio>
#include <cstring>

// OCCT reports progress on std::cout; stdout must carry only our output.
static inline void occt_quiet()
{
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
}

// An IGES file's shape; false when OCCT cannot read it.
static inline bool occt_read_iges(const char *path, TopoDS_Shape &shape)
{
    IGESControl_Reader rd;
    // Keep the B-spline as written: no splitting of C0 patches into faces.
    Interface_Static::SetIVal("read.iges.bspline.continuity", 0);
    if (rd.ReadFile(path) != IFSelect_RetDone)
        return false;
    rd.TransferRoots();
    shape = rd.OneShape();
    return true;
}

// A STEP file's shape, with its roots and how many transferred (may be NULL).
static inline bool occt_read_step(const char *path, TopoDS_Shape &shape, int *roots = nullptr,
                                  int *done = nullptr)
{
    STEPControl_Reader rd;
    if (rd.ReadFile(path) != IFSelect_RetDone)
        return false;
    int nr = rd.NbRootsForTransfer();
    int nd = rd.TransferRoots();
    if (roots)
        *roots = nr;
    if (done)
        *done = nd;
    shape = rd.OneShape();
    return true;
}

static inline bool occt_ends(const char *p, const char *e)
{
    size_t n = std::strlen(p), m = std::strlen(e);
    if (n < m)
        return false;
    for (size_t i = 0; i < m; i++)
        if (std::tolower((unsigned char)p[n - m + i]) != e[i])
            return false;
    return true;
}

static inline bool occt_is_step(const char *path)
{
    return occt_ends(path, ".stp") || occt_ends(path, ".step");
}

// IGES or STEP by the file's extension (.stp, .step: STEP).
static inline bool occt_read(const char *path, TopoDS_Shape &shape)
{
    return occt_is_step(path) ? occt_read_step(path, shape) : occt_read_iges(path, shape);
}

static inline int occt_count(const TopoDS_Shape &s, TopAbs_ShapeEnum what)
{
    int n = 0;
    for (TopExp_Explorer e(s, what); e.More(); e.Next())
        n++;
    return n;
}

// The shape's first face; false when it has none.
static inline bool occt_first_face(const TopoDS_Shape &shape, TopoDS_Face &face)
{
    TopExp_Explorer ex(shape, TopAbs_FACE);
    if (!ex.More())
        return false;
    face = TopoDS::Face(ex.Current());
    return true;
}

// "degrees P Q, poles N x M, rational R S, location identity|non-identity"
// of the B-spline under surf (a rectangular trim looked through), or "surface
// type T, not Geom_BSplineSurface".
static inline void occt_describe(const Handle(Geom_Surface) & surf, const TopLoc_Location &loc,
                                 char *buf, size_t n)
{
    Handle(Geom_Surface) basis = surf;
    Handle(Geom_RectangularTrimmedSurface) tr =
        Handle(Geom_RectangularTrimmedSurface)::DownCast(surf);
    if (!tr.IsNull())
        basis = tr->BasisSurface();
    Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(basis);
    if (bs.IsNull())
        std::snprintf(buf, n, "surface type %s, not Geom_BSplineSurface",
                      basis->DynamicType()->Name());
    else
        std::snprintf(buf, n, "degrees %d %d, poles %d x %d, rational %d %d, location %s",
                      bs->UDegree(), bs->VDegree(), bs->NbUPoles(), bs->NbVPoles(),
                      (int)bs->IsURational(), (int)bs->IsVRational(),
                      loc.IsIdentity() ? "identity" : "non-identity");
}

// For each "u v" line of stdin, the surface there (moved by loc) as
// "PREFIXx y z" with %.17g; other lines are skipped.
static inline void occt_eval_stdin(const Handle(Geom_Surface) & surf, const TopLoc_Location &loc,
                                   const char *prefix)
{
    char line[512];
    while (std::fgets(line, sizeof line, stdin)) {
        double u, v;
        if (std::sscanf(line, "%lf %lf", &u, &v) != 2)
            continue;
        gp_Pnt p;
        surf->D0(u, v, p);
        if (!loc.IsIdentity())
            p.Transform(loc.Transformation());
        std::printf("%s%.17g %.17g %.17g\n", prefix, p.X(), p.Y(), p.Z());
    }
}

#endif
