/* SPDX-License-Identifier: MIT */
// occt_trim.cpp: trimmed faces through OpenCASCADE, as the independent side
// of tests/cli/trim.sh.
// `occt_trim make OUT.igs [OUT.stp]`: OCCT builds and writes a trimmed
// B-spline face: a bicubic 6 x 6 surface on [0,1]^2 cut by a circle (two
// rational arcs, outer boundary) with a quadrilateral hole (four lines),
// every parameter-space curve a Geom2d_BSplineCurve; 3-D edges by
// BRepLib::BuildCurves3d; IGES in faces mode (144/142), STEP as a shell.
// `occt_trim read FILE`: reads an IGES or STEP file (by extension) and
// prints on stdout "faces N", "valid 0|1", per wire (outer first)
// "wire K edges E length L bbox U0 V0 U1 V1" (uv length and box of its
// parameter-space curves) and "pt K U V" samples (9 per edge), then for
// each "u v" line on stdin the face's surface at (u, v) as "xyz X Y Z".
#include "occt_shape.hxx"

#include <BRepAdaptor_Curve2d.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepLib.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <GCE2d_MakeSegment.hxx>
#include <GCPnts_AbscissaPoint.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_Circle.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax2d.hxx>
#include <gp_Circ2d.hxx>

#include <cmath>
#include <vector>

static Handle(Geom_BSplineSurface) nominal()
{
    TColgp_Array2OfPnt P(1, 6, 1, 6);
    for (int i = 1; i <= 6; i++)
        for (int j = 1; j <= 6; j++) {
            double x = 20.0 * (i - 1), y = 16.0 * (j - 1);
            P(i, j) = gp_Pnt(x, y, 3.0 * std::sin(0.05 * x) * std::cos(0.07 * y) + 0.01 * x * y);
        }
    TColStd_Array1OfReal K(1, 4);
    TColStd_Array1OfInteger M(1, 4);
    for (int k = 1; k <= 4; k++) {
        K(k) = (k - 1) / 3.0;
        M(k) = k == 1 || k == 4 ? 4 : 1;
    }
    return new Geom_BSplineSurface(P, K, K, M, M, 3, 3);
}

static Handle(Geom2d_BSplineCurve) arc(double a0, double a1)
{
    Handle(Geom2d_Circle) c = new Geom2d_Circle(gp_Ax2d(gp_Pnt2d(0.5, 0.5), gp_Dir2d(1, 0)), 0.4);
    return Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(c, a0, a1));
}

static Handle(Geom2d_BSplineCurve) seg(double u0, double v0, double u1, double v1)
{
    return Geom2dConvert::CurveToBSplineCurve(
        GCE2d_MakeSegment(gp_Pnt2d(u0, v0), gp_Pnt2d(u1, v1)).Value());
}

static int make(const char *igs, const char *stp)
{
    Handle(Geom_BSplineSurface) S = nominal();
    BRepBuilderAPI_MakeWire outer(BRepBuilderAPI_MakeEdge(arc(0, M_PI), S).Edge(),
                                  BRepBuilderAPI_MakeEdge(arc(M_PI, 2 * M_PI), S).Edge());
    // The hole clockwise (a hole's wire runs against the outer one).
    const double q[5][2] = {{0.4, 0.35}, {0.42, 0.62}, {0.63, 0.6}, {0.6, 0.38}, {0.4, 0.35}};
    BRepBuilderAPI_MakeWire inner;
    for (int k = 0; k < 4; k++)
        inner.Add(BRepBuilderAPI_MakeEdge(seg(q[k][0], q[k][1], q[k + 1][0], q[k + 1][1]), S).Edge());
    BRepBuilderAPI_MakeFace mf(S, outer.Wire());
    mf.Add(inner.Wire());
    TopoDS_Face face = mf.Face();
    BRepLib::BuildCurves3d(face);
    std::fprintf(stderr, "occt_trim: made face, BRepCheck valid %d\n",
                 (int)BRepCheck_Analyzer(face).IsValid());
    IGESControl_Controller::Init();
    IGESControl_Writer w("MM", 0); // faces mode: 144 over the 128
    w.AddShape(face);
    w.ComputeModel();
    if (!w.Write(igs)) {
        std::fprintf(stderr, "occt_trim: cannot write %s\n", igs);
        return 2;
    }
    if (stp) {
        STEPControl_Writer sw;
        Interface_Static::SetCVal("write.step.unit", "MM");
        if (sw.Transfer(face, STEPControl_AsIs) != IFSelect_RetDone ||
            sw.Write(stp) != IFSelect_RetDone) {
            std::fprintf(stderr, "occt_trim: cannot write %s\n", stp);
            return 2;
        }
    }
    return 0;
}

static void wire_out(int k, const TopoDS_Wire &w, const TopoDS_Face &f)
{
    double len = 0, b[4] = {1e300, 1e300, -1e300, -1e300};
    int ne = 0;
    std::vector<double> pts;
    for (BRepTools_WireExplorer ex(w, f); ex.More(); ex.Next()) {
        BRepAdaptor_Curve2d c(ex.Current(), f);
        len += GCPnts_AbscissaPoint::Length(c, 1e-12);
        ne++;
        for (int i = 0; i <= 8; i++) {
            gp_Pnt2d p = c.Value(c.FirstParameter() + (c.LastParameter() - c.FirstParameter()) * i / 8.0);
            pts.push_back(p.X());
            pts.push_back(p.Y());
        }
        for (int i = 0; i <= 400; i++) { // the box: dense samples
            gp_Pnt2d p = c.Value(c.FirstParameter() + (c.LastParameter() - c.FirstParameter()) * i / 400.0);
            b[0] = std::fmin(b[0], p.X()), b[1] = std::fmin(b[1], p.Y());
            b[2] = std::fmax(b[2], p.X()), b[3] = std::fmax(b[3], p.Y());
        }
    }
    std::printf("wire %d edges %d length %.17g bbox %.17g %.17g %.17g %.17g\n", k, ne, len, b[0],
                b[1], b[2], b[3]);
    for (size_t i = 0; i < pts.size(); i += 2)
        std::printf("pt %d %.17g %.17g\n", k, pts[i], pts[i + 1]);
}

static int read(const char *path)
{
    TopoDS_Shape shape;
    if (!occt_read(path, shape))
        return 2;
    std::printf("faces %d\n", occt_count(shape, TopAbs_FACE));
    TopoDS_Face face;
    if (!occt_first_face(shape, face))
        return 2;
    std::printf("valid %d\n", (int)BRepCheck_Analyzer(face).IsValid());
    TopoDS_Wire outer = BRepTools::OuterWire(face);
    wire_out(0, outer, face);
    int k = 1;
    for (TopExp_Explorer e(face, TopAbs_WIRE); e.More(); e.Next())
        if (!e.Current().IsSame(outer))
            wire_out(k++, TopoDS::Wire(e.Current()), face);
    TopLoc_Location loc;
    Handle(Geom_Surface) surf = BRep_Tool::Surface(face, loc);
    occt_eval_stdin(surf, loc, "xyz ");
    return 0;
}

int main(int argc, char **argv)
{
    occt_quiet();
    try {
        if (argc >= 3 && !std::strcmp(argv[1], "make"))
            return make(argv[2], argc > 3 ? argv[3] : nullptr);
        if (argc == 3 && !std::strcmp(argv[1], "read"))
            return read(argv[2]);
    } catch (Standard_Failure &e) {
        std::fprintf(stderr, "occt_trim: OpenCASCADE exception: %s\n", e.GetMessageString());
        return 2;
    }
    std::fprintf(stderr, "usage: occt_trim make OUT.igs [OUT.stp] | occt_trim read FILE\n");
    return 1;
}
